#include <crackvis/cracks/bond_graph.hpp>
#include <crackvis/dem/lattice_generator.hpp>
#include <crackvis/render/probe_scene.hpp>

namespace crackvis::render {

namespace {

// The block, its step (the bonds across the middle broken), the crack the
// description's method finds there, and the arrays a colour-by may read.
struct ProbeSpecimen {
  dem::LatticeBlock block;
  std::vector<std::uint8_t> bondState;
  cracks::CrackMesh mesh;
  std::vector<std::array<float, 3>> velocities;
  std::vector<float> particleExtra;
  std::vector<float> bondExtra;

  SceneInput input() const {
    SceneInput in;
    in.lattice = &block.lattice;
    in.step.positions = block.positions;
    in.step.bondState = bondState;
    in.step.radius = block.lattice.radius;
    in.initialPositions = block.positions;
    in.velocities = velocities;
    in.cracks = &mesh;
    in.particleExtra = particleExtra;
    in.bondExtra = bondExtra;
    in.stepIndex = 0;
    in.stepCount = 1;
    return in;
  }
};

Result<std::unique_ptr<ProbeSpecimen>> makeProbeSpecimen(cracks::Method method) {
  dem::BlockSpec spec;
  spec.sites = {5, 5, 5};
  spec.radius = 0.5;
  auto block = dem::generateBlock(spec);
  if (!block) {
    return block.status();
  }
  auto probe = std::make_unique<ProbeSpecimen>();
  probe->block = std::move(block).value();
  const auto& bonds = probe->block.lattice.bonds;
  const auto& positions = probe->block.positions;
  probe->bondState.assign(bonds.size(), 0);
  const double middle = 0.5 * probe->block.extent.x;
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    const double a = positions[static_cast<std::size_t>(bonds[b].first)].x - middle;
    const double c = positions[static_cast<std::size_t>(bonds[b].second)].x - middle;
    probe->bondState[b] = a * c < 0.0 ? 1 : 0;
  }
  probe->velocities.assign(positions.size(), {0.0f, 0.0f, 0.0f});
  probe->particleExtra.assign(positions.size(), 0.0f);
  probe->bondExtra.assign(bonds.size(), 0.0f);
  const cracks::BondGraph graph(probe->block.lattice.particleCount(), bonds);
  auto extractor = cracks::makeExtractor(method, graph, 3);
  CRACKVIS_RETURN_IF_ERROR(extractor->extract(probe->input().step, probe->mesh));
  return probe;
}

}  // namespace

Status renderProbeScene(SceneRenderer& renderer, int width, int height, Image& out) {
  pipeline::PipelineDescription description;
  description.view.width = width;
  description.view.height = height;
  auto probe = makeProbeSpecimen(description.cracks.method);
  if (!probe) {
    return probe.status();
  }
  return renderer.render(description, (*probe)->input(), out);
}

Status rehearseOnProbe(SceneRenderer& renderer, const pipeline::PipelineDescription& description) {
  auto probe = makeProbeSpecimen(description.cracks.method);
  if (!probe) {
    return probe.status();
  }
  return renderer.rehearse(description, (*probe)->input());
}

}  // namespace crackvis::render
