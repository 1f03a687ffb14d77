#include <charconv>

#include <fmt/format.h>

#include <crackvis/cracks/dem_series.hpp>

namespace crackvis::cracks {

Result<std::unique_ptr<DemSeries>> DemSeries::open(const std::string& path) {
  auto reader = dem::DemFileReader::open(path);
  if (!reader) {
    return reader.status();
  }
  std::unique_ptr<DemSeries> series(new DemSeries(std::move(reader).value()));
  auto lattice = series->m_reader.readLattice();
  if (!lattice) {
    return lattice.status();
  }
  series->m_lattice = std::move(lattice).value();
  auto breakSteps = series->m_reader.readBreakSteps();
  if (!breakSteps) {
    return breakSteps.status();
  }
  series->m_breakSteps = std::move(breakSteps).value();
  series->m_graph =
      std::make_unique<BondGraph>(series->m_lattice.particleCount(), series->m_lattice.bonds);
  return series;
}

Result<StepInput> DemSeries::load(int step) {
  auto state = m_reader.readStep(step);
  if (!state) {
    return state.status();
  }
  m_state = std::move(state).value();
  // The first step is the reference configuration a triangulation is made in.
  if (m_reference.empty()) {
    if (step == 0) {
      m_reference = m_state.positions;
    } else {
      auto first = m_reader.readStep(0);
      if (!first) {
        return first.status();
      }
      m_reference = std::move(first->positions);
    }
  }
  return StepInput{m_state.positions, m_state.bondState, m_lattice.radius,
                   m_state.bondForce, m_breakSteps,      m_reference};
}

Result<std::vector<int>> parseStepRange(const std::string& text, int stepCount) {
  std::vector<long> parts;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(':', start), text.size());
    long value = 0;
    const char* first = text.data() + start;
    const char* last = text.data() + end;
    const auto [ptr, error] = std::from_chars(first, last, value);
    if (error != std::errc() || ptr != last || first == last) {
      return invalidArgument(
          fmt::format("step range '{}': expected A, A:B or A:B:K with integers", text));
    }
    parts.push_back(value);
    start = end + 1;
  }
  if (parts.size() > 3) {
    return invalidArgument(fmt::format("step range '{}': expected A, A:B or A:B:K", text));
  }
  if (stepCount <= 0) {
    return invalidArgument("the file has no steps");
  }
  auto resolve = [&](long value) { return value < 0 ? stepCount + value : value; };
  const long first = resolve(parts[0]);
  const long last = parts.size() >= 2 ? resolve(parts[1]) : first;
  const long stride = parts.size() == 3 ? parts[2] : 1;
  if (stride <= 0) {
    return invalidArgument(fmt::format("step range '{}': the stride must be positive", text));
  }
  if (first < 0 || first >= stepCount || last < 0 || last >= stepCount) {
    return invalidArgument(
        fmt::format("step range '{}' is outside the file's steps 0..{}", text, stepCount - 1));
  }
  if (last < first) {
    return invalidArgument(fmt::format("step range '{}' is empty (B < A)", text));
  }
  std::vector<int> steps;
  for (long s = first; s <= last; s += stride) {
    steps.push_back(static_cast<int>(s));
  }
  return steps;
}

}  // namespace crackvis::cracks
