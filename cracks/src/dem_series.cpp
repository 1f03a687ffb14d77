#include <charconv>

#include <fmt/format.h>

#include <crackvis/cracks/dem_series.hpp>

namespace crackvis::cracks {

Result<std::unique_ptr<DemSeries>> DemSeries::open(const std::string& path) {
  auto reader = dem::DemFileReader::openGuarded(path);
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
  return StepInput{m_state.positions,
                   m_state.bondState,
                   m_lattice.radius,
                   m_state.bondForce,
                   m_breakSteps,
                   m_reference,
                   {},
                   {}};
}

}  // namespace crackvis::cracks
