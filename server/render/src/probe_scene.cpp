#include <crackvis/cracks/bond_graph.hpp>
#include <crackvis/dem/lattice_generator.hpp>
#include <crackvis/render/probe_scene.hpp>

namespace crackvis::render {

Status renderProbeScene(SceneRenderer& renderer, int width, int height, Image& out) {
  dem::BlockSpec spec;
  spec.sites = {5, 5, 5};
  spec.radius = 0.5;
  auto block = dem::generateBlock(spec);
  if (!block) {
    return block.status();
  }
  const auto& bonds = block->lattice.bonds;
  std::vector<std::uint8_t> state(bonds.size(), 0);
  const double middle = 0.5 * block->extent.x;
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    const double a = block->positions[static_cast<std::size_t>(bonds[b].first)].x - middle;
    const double c = block->positions[static_cast<std::size_t>(bonds[b].second)].x - middle;
    state[b] = a * c < 0.0 ? 1 : 0;
  }
  const cracks::BondGraph graph(block->lattice.particleCount(), bonds);
  cracks::StepInput step;
  step.positions = block->positions;
  step.bondState = state;
  step.radius = block->lattice.radius;
  auto extractor = cracks::makeExtractor(cracks::Method::kCellCut, graph, 3);
  cracks::CrackMesh mesh;
  CRACKVIS_RETURN_IF_ERROR(extractor->extract(step, mesh));
  SceneInput input;
  input.lattice = &block->lattice;
  input.step = step;
  input.cracks = &mesh;
  pipeline::PipelineDescription description;
  description.view.width = width;
  description.view.height = height;
  return renderer.render(description, input, out);
}

}  // namespace crackvis::render
