#include "crack_history.hpp"

#include <algorithm>
#include <span>

#include <fmt/format.h>

namespace crackvis::service {

namespace {

// Every step's main plane: a history may be shown up to any step, and its
// front's axes follow the last shown main crack's plane.
analysis::AnalysisOptions everyStepsPlane() {
  analysis::AnalysisOptions options;
  options.mainPlaneEachStep = true;
  return options;
}

// The default options with "auto" settled by the file's record, as a view
// settles it (ScenePipeline).
cracks::ExtractOptions extractOptionsFor(const source::StepSource& source) {
  cracks::ExtractOptions options;
  options.decomposition =
      cracks::settledByFile(options.decomposition, source.recordedDecomposition());
  return options;
}

}  // namespace

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
      m_extractor(cracks::makeExtractor(method, m_graph, m_source->lattice().dimension,
                                        extractOptionsFor(*m_source))),
      m_analyses(m_source->lattice(), everyStepsPlane()) {}

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

Result<CrackHistoryRun::Series> CrackHistoryRun::series(
    int steps, std::chrono::system_clock::time_point deadline) {
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
  return Series{analysis::crackSeries(shown, front), std::max(0, last - before)};
}

std::string FinishedSeries::key(const std::string& revision, cracks::Method method,
                                bool recordedModes, int steps) {
  return fmt::format("{}\n{}\n{}\n{}", revision, cracks::toString(method), recordedModes, steps);
}

std::optional<std::vector<analysis::NamedSeries>> FinishedSeries::find(const std::string& key) {
  const std::lock_guard lock(m_mutex);
  const auto found = m_byKey.find(key);
  if (found == m_byKey.end()) {
    return std::nullopt;
  }
  m_recent.splice(m_recent.begin(), m_recent, found->second);
  return found->second->series;
}

void FinishedSeries::store(const std::string& key, std::vector<analysis::NamedSeries> series) {
  std::size_t bytes = key.size();
  for (const analysis::NamedSeries& one : series) {
    bytes += one.name.size() + one.values.size() * sizeof(double);
  }
  if (bytes > kMaxBytes) {
    return;
  }
  const std::lock_guard lock(m_mutex);
  if (const auto found = m_byKey.find(key); found != m_byKey.end()) {
    m_bytes -= found->second->bytes;
    m_recent.erase(found->second);
    m_byKey.erase(found);
  }
  evictTo(kMaxBytes - bytes);
  m_bytes += bytes;
  m_recent.push_front({key, std::move(series), bytes});
  m_byKey.emplace(key, m_recent.begin());
}

std::size_t FinishedSeries::entries() const {
  const std::lock_guard lock(m_mutex);
  return m_recent.size();
}

void FinishedSeries::evictTo(std::size_t bytes) {
  while (m_bytes > bytes && !m_recent.empty()) {
    m_bytes -= m_recent.back().bytes;
    m_byKey.erase(m_recent.back().key);
    m_recent.pop_back();
  }
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
