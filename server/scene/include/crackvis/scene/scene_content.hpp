// What a scene draws, decided without GL: the particles a viewer can see
// (culling), the values particles are coloured by (damage among them), which
// crack primitives go into which layer, the decomposition's edges and the
// bonds shown. The renderer (server/render) turns these into VTK actors;
// tests check them directly rather than through pixels.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include <crackvis/cracks/crack_mesh.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/scene/scene_input.hpp>

namespace crackvis::scene {

// The particles a viewer can see when they are opaque and unclipped: those on
// the lattice's boundary (fewer bonds than the most) or at a broken bond, and
// two more layers of bonded neighbours below them. All particles when they
// are translucent or clipped, or the step's bond states do not match the
// lattice. Ascending indices.
std::vector<dem::ParticleIndex> visibleParticles(const pipeline::ParticlesDescription& particles,
                                                 const SceneInput& input);

// The per-particle value a colour-by names (0 for kSolid); kDamage: the share
// of a particle's bonds that are broken.
std::vector<double> particleValues(const pipeline::ParticlesDescription& particles,
                                   const SceneInput& input);

// The primitives of `mesh` that `keep(k)` selects (k in VTK order: vertices,
// lines, polygons, volume cells), with their cell data; points are shared.
cracks::CrackMesh selectPrimitives(const cracks::CrackMesh& mesh,
                                   const std::function<bool(std::size_t)>& keep);

// The crack mesh split into the layers drawn differently: cracks (broken,
// consistent bonds), inconsistency marks (local Voronoi) and intact faces
// (the local decomposition). A layer the description does not show is empty.
struct CrackLayers {
  cracks::CrackMesh cracks;
  cracks::CrackMesh marks;
  cracks::CrackMesh intact;
};
CrackLayers crackLayers(const pipeline::PipelineDescription& description,
                        const cracks::CrackMesh& mesh);

// The edges of the decomposition's cells, ascending (empty without a
// decomposition), as indices into the decomposition's graph: the file's
// bonds, then on a triangulated packing the triangulation's never-bonded
// edges (beyond the lattice's M bonds; draw them through
// decomposition->graph()).
std::vector<dem::BondIndex> decompositionBonds(const SceneInput& input);

// The bonds drawn (all or only broken ones) and the value each is coloured by.
struct BondLines {
  std::vector<dem::BondIndex> bonds;
  std::vector<double> values;
};
BondLines bondLines(const pipeline::BondsDescription& bonds, const SceneInput& input);

}  // namespace crackvis::scene
