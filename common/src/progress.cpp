#include <algorithm>
#include <cmath>

#include <unistd.h>

#include <crackvis/common/progress.hpp>

namespace crackvis {
namespace {

std::string formatSeconds(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) {
    return "--:--";
  }
  const auto total = static_cast<long>(std::lround(seconds));
  char buffer[32];
  if (total >= 3600) {
    std::snprintf(buffer, sizeof buffer, "%ld:%02ld:%02ld", total / 3600, total / 60 % 60,
                  total % 60);
  } else {
    std::snprintf(buffer, sizeof buffer, "%02ld:%02ld", total / 60, total % 60);
  }
  return buffer;
}

}  // namespace

ProgressBar::ProgressBar(std::string label, std::int64_t total, std::FILE* out)
    : m_label(std::move(label)),
      m_total(std::max<std::int64_t>(total, 1)),
      m_out(out),
      m_isTerminal(isatty(fileno(out)) == 1),
      m_start(std::chrono::steady_clock::now()),
      m_lastDraw(m_start - std::chrono::seconds(1)) {}

ProgressBar::~ProgressBar() {
  finish();
}

void ProgressBar::update(std::int64_t done, const std::string& detail) {
  m_done = std::clamp<std::int64_t>(done, 0, m_total);
  m_lastDetail = detail;
  draw(detail, false);
}

void ProgressBar::finish() {
  if (m_finished) {
    return;
  }
  m_finished = true;
  draw(m_lastDetail, true);
}

void ProgressBar::draw(const std::string& detail, bool final) {
  if (!m_enabled) {
    return;
  }
  const auto now = std::chrono::steady_clock::now();
  const double fraction = static_cast<double>(m_done) / static_cast<double>(m_total);
  const double elapsed = std::chrono::duration<double>(now - m_start).count();
  const double eta = m_done > 0 ? elapsed * (1.0 - fraction) / fraction : -1.0;

  if (!m_isTerminal) {
    // Plain logs: one line per completed tenth, and the final line.
    const int decile = static_cast<int>(fraction * 10.0);
    // One line per tenth; the final line only if the last one was not 100 %.
    if (decile == m_lastDecile && (!final || m_done == m_total)) {
      return;
    }
    m_lastDecile = decile;
    std::fprintf(m_out, "%s: %3d%% (%lld/%lld) elapsed %s%s%s\n", m_label.c_str(),
                 static_cast<int>(fraction * 100.0), static_cast<long long>(m_done),
                 static_cast<long long>(m_total), formatSeconds(elapsed).c_str(),
                 detail.empty() ? "" : ", ", detail.c_str());
    std::fflush(m_out);
    return;
  }
  // Terminals: redraw at most ten times a second.
  if (!final && now - m_lastDraw < std::chrono::milliseconds(100)) {
    return;
  }
  m_lastDraw = now;
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(fraction * kWidth);
  std::string bar(static_cast<size_t>(filled), '#');
  bar.resize(kWidth, '.');
  std::fprintf(m_out, "\r%s [%s] %3d%% %lld/%lld  %s ETA %s%s%s\x1b[K", m_label.c_str(),
               bar.c_str(), static_cast<int>(fraction * 100.0), static_cast<long long>(m_done),
               static_cast<long long>(m_total), formatSeconds(elapsed).c_str(),
               final ? "00:00" : formatSeconds(eta).c_str(), detail.empty() ? "" : "  ",
               detail.c_str());
  if (final) {
    std::fputc('\n', m_out);
  }
  std::fflush(m_out);
}

}  // namespace crackvis
