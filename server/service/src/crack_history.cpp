#include "crack_history.hpp"

#include <algorithm>
#include <span>

#include <fmt/format.h>

namespace crackvis::service {

Result<std::unique_ptr<CrackHistoryRun>> CrackHistoryRun::start(
    std::unique_ptr<source::StepSource> source, cracks::Method method, bool recordedModes) {
  // The modes need each bond's force and break step where the file has them.
  source::ExtraArrays extras;
  extras.bondForce = true;
  extras.breakStep = true;
  if (recordedModes) {
    extras.bondExtra = std::string(dem::kBreakModeArray);
  }
  CRACKVIS_RETURN_IF_ERROR(source->setExtraArrays(extras));
  return std::unique_ptr<CrackHistoryRun>(
      new CrackHistoryRun(std::move(source), method, recordedModes));
}

CrackHistoryRun::CrackHistoryRun(std::unique_ptr<source::StepSource> source, cracks::Method method,
                                 bool recordedModes)
    : m_source(std::move(source)),
      m_method(method),
      m_recordedModes(recordedModes),
      m_graph(m_source->lattice().particleCount(), m_source->lattice().bonds),
      m_extractor(cracks::makeExtractor(method, m_graph, m_source->lattice().dimension)),
      m_analyses(m_source->lattice(), {}) {}

bool CrackHistoryRun::continues(const std::string& file, cracks::Method method,
                                bool recordedModes) const {
  return m_source->file() == file && m_method == method && m_recordedModes == recordedModes;
}

Status CrackHistoryRun::analyseStep(int k) {
  auto step = m_source->read(k);
  CRACKVIS_RETURN_IF_ERROR(step.status());
  if (k == 0) {
    m_reference = step->positions;
  }
  const dem::Lattice& lattice = m_source->lattice();
  const cracks::StepInput input{step->positions,
                                step->bondState,
                                lattice.radius,
                                step->bondForce,
                                m_source->breakSteps(),
                                m_reference,
                                {},
                                {}};
  CRACKVIS_RETURN_IF_ERROR(m_extractor->extract(input, m_mesh));
  m_modes.assign(step->bondExtra.begin(), step->bondExtra.end());
  m_steps.push_back(m_analyses.analyse(k, step->time, input, m_reference, m_mesh, m_modes));
  return Status::ok();
}

Status CrackHistoryRun::addSeries(int steps, std::chrono::system_clock::time_point deadline,
                                  v1::StepHistoryResponse& response) {
  if (live()) {
    CRACKVIS_RETURN_IF_ERROR(m_source->refresh().status());
  }
  // The response's history was read first: never more steps than it has.
  const int last = std::min(steps, m_source->stepCount());
  const auto before = static_cast<int>(m_steps.size());
  for (int k = before; k < last; ++k) {
    if (std::chrono::system_clock::now() > deadline) {
      return deadlineExceeded(
          fmt::format("{}: the crack's numbers reached step {} of {} by the call's deadline",
                      m_source->file(), k, last));
    }
    CRACKVIS_RETURN_IF_ERROR(analyseStep(k));
  }
  const auto shown = std::span<const analysis::StepAnalysis>(m_steps).first(
      std::min(static_cast<std::size_t>(std::max(last, 0)), m_steps.size()));
  const int dimension = m_source->lattice().dimension;
  const analysis::CrackFront front = analysis::crackFront(shown, dimension);
  for (const analysis::NamedSeries& series : analysis::crackSeries(shown, front)) {
    auto* out = response.add_scalars();
    out->set_name(series.name);
    out->mutable_values()->Add(series.values.begin(), series.values.end());
  }
  response.set_crack_steps_computed(std::max(0, last - before));
  return Status::ok();
}

Status CrackHistories::enter(const std::string& user) {
  const std::lock_guard lock(m_mutex);
  if (!m_running.insert(user).second) {
    return resourceExhausted(
        "the crack's numbers of another file of yours are being computed: one at a time per user");
  }
  return Status::ok();
}

void CrackHistories::leave(const std::string& user) {
  const std::lock_guard lock(m_mutex);
  m_running.erase(user);
}

std::unique_ptr<CrackHistoryRun> CrackHistories::take(const std::string& user,
                                                      const std::string& file,
                                                      cracks::Method method, bool recordedModes) {
  std::unique_ptr<CrackHistoryRun> run;
  {
    const std::lock_guard lock(m_mutex);
    const auto found = m_kept.find(user);
    if (found == m_kept.end()) {
      return nullptr;
    }
    run = std::move(found->second.run);
    m_kept.erase(found);
  }
  // A run of another file or method is dropped outside the lock.
  return run->continues(file, method, recordedModes) ? std::move(run) : nullptr;
}

void CrackHistories::keep(const std::string& user, std::unique_ptr<CrackHistoryRun> run) {
  const std::lock_guard lock(m_mutex);
  m_kept[user] = {std::move(run), std::chrono::steady_clock::now()};
}

void CrackHistories::dropIdle() {
  std::vector<std::unique_ptr<CrackHistoryRun>> dropped;
  const auto now = std::chrono::steady_clock::now();
  {
    const std::lock_guard lock(m_mutex);
    for (auto it = m_kept.begin(); it != m_kept.end();) {
      if (now - it->second.used > kIdleRun) {
        dropped.push_back(std::move(it->second.run));
        it = m_kept.erase(it);
      } else {
        ++it;
      }
    }
  }
}

}  // namespace crackvis::service
