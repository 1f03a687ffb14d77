#include <algorithm>
#include <thread>

#include <crackvis/service/render_turns.hpp>

namespace crackvis::service {

namespace {
int defaultAtOnce() {
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}
}  // namespace

RenderTurns::RenderTurns(int atOnce) : m_atOnce(atOnce > 0 ? atOnce : defaultAtOnce()) {}

RenderTurns::Turn RenderTurns::take() {
  std::unique_lock lock(m_mutex);
  const bool crowded = m_serving != m_nextTicket || m_rendering > 0;
  const std::uint64_t ticket = m_nextTicket++;
  m_changed.wait(lock, [&] { return ticket == m_serving && m_rendering < m_atOnce; });
  ++m_serving;
  ++m_rendering;
  // The next in line may also fit (atOnce > 1).
  m_changed.notify_all();
  return Turn(this, crowded);
}

void RenderTurns::release() {
  {
    std::lock_guard lock(m_mutex);
    --m_rendering;
  }
  m_changed.notify_all();
}

RenderTurns::Turn::~Turn() {
  if (m_turns != nullptr) {
    m_turns->release();
  }
}

}  // namespace crackvis::service
