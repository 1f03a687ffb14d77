#include "crack_history.hpp"

#include <fmt/format.h>

#include <crackvis/analysis/growth.hpp>
#include <crackvis/cracks/bond_graph.hpp>
#include <crackvis/cracks/extractor.hpp>

namespace crackvis::service {

Status addCrackSeries(source::StepSource& source, cracks::Method method, bool recordedModes,
                      std::chrono::system_clock::time_point deadline,
                      v1::StepHistoryResponse& response) {
  // The modes need each bond's force and break step where the file has them.
  source::ExtraArrays extras;
  extras.bondForce = true;
  extras.breakStep = true;
  if (recordedModes) {
    extras.bondExtra = std::string(dem::kBreakModeArray);
  }
  CRACKVIS_RETURN_IF_ERROR(source.setExtraArrays(extras));
  std::vector<double> modes;
  const dem::Lattice& lattice = source.lattice();
  const cracks::BondGraph graph(lattice.particleCount(), lattice.bonds);
  auto extractor = cracks::makeExtractor(method, graph, lattice.dimension);
  analysis::CrackAnalysis analyses(lattice, {});
  std::vector<analysis::StepAnalysis> steps;
  std::vector<dem::Vec3> reference;
  cracks::CrackMesh mesh;
  for (int k = 0; k < source.stepCount(); ++k) {
    if (std::chrono::system_clock::now() > deadline) {
      return deadlineExceeded(
          fmt::format("{}: the crack's numbers reached step {} of {} by the "
                      "call's deadline",
                      source.file(), k, source.stepCount()));
    }
    auto step = source.read(k);
    CRACKVIS_RETURN_IF_ERROR(step.status());
    if (k == 0) {
      reference = step->positions;
    }
    const cracks::StepInput input{step->positions,
                                  step->bondState,
                                  lattice.radius,
                                  step->bondForce,
                                  source.breakSteps(),
                                  reference,
                                  {},
                                  {}};
    CRACKVIS_RETURN_IF_ERROR(extractor->extract(input, mesh));
    modes.assign(step->bondExtra.begin(), step->bondExtra.end());
    steps.push_back(analyses.analyse(k, step->time, input, reference, mesh, modes));
  }
  const analysis::CrackFront front = analysis::crackFront(steps, lattice.dimension);
  for (const analysis::NamedSeries& series : analysis::crackSeries(steps, front)) {
    auto* out = response.add_scalars();
    out->set_name(series.name);
    out->mutable_values()->Add(series.values.begin(), series.values.end());
  }
  return Status::ok();
}

Status CrackHistoryGate::enter(const std::string& user) {
  const std::lock_guard lock(m_mutex);
  if (!m_running.insert(user).second) {
    return resourceExhausted(
        "the crack's numbers of another file of yours are being computed: one at a time per user");
  }
  return Status::ok();
}

void CrackHistoryGate::leave(const std::string& user) {
  const std::lock_guard lock(m_mutex);
  m_running.erase(user);
}

}  // namespace crackvis::service
