// What a scene draws, decided without GL: the particles a viewer can see
// (culling), the values particles are coloured by (damage among them), which
// crack primitives go into which layer, the decomposition's edges and the
// bonds shown. The renderer (server/render) turns these into VTK actors;
// tests check them directly rather than through pixels.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <crackvis/cracks/crack_mesh.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/scene_model/scene_input.hpp>

namespace crackvis::scene {

// The particles a viewer can see when they are opaque and unclipped: those on
// the lattice's boundary (fewer bonds than the most) or at a broken bond, and
// two more layers of bonded neighbours below them. All particles when they
// are translucent, clipped or thresholded, or the step's bond states do not
// match the lattice. Ascending indices; the threshold, when described, keeps
// only the particles whose value lies in it.
std::vector<dem::ParticleIndex> visibleParticles(const pipeline::ParticlesDescription& particles,
                                                 const SceneInput& input);

// The per-particle value a colour-by names (0 for kSolid); kDamage: the share
// of a particle's bonds that are broken.
std::vector<double> particleValues(const pipeline::ParticlesDescription& particles,
                                   const SceneInput& input);
std::vector<double> particleValues(pipeline::ParticleColourBy by, const SceneInput& input);

// The cell array of the crack mesh a crack colour-by names (nullptr: solid).
// Cell attribute's cells carry their own: first_broken_bond for the bond id,
// broken_bonds for the state.
const char* crackArrayName(pipeline::CrackColourBy by,
                           cracks::Method method = cracks::Method::kLocalVoronoi);

// A coloured quantity as a legend shows it: the title with its unit (SI, as
// crackvis-dem stores them), and whether the values are whole numbers
// (steps, ids, ranks, states), which the labels then show without decimals.
struct Quantity {
  std::string title;
  bool integral = false;
};
Quantity particleQuantity(const pipeline::ParticlesDescription& particles);
Quantity crackQuantity(pipeline::CrackColourBy by,
                       cracks::Method method = cracks::Method::kLocalVoronoi);
Quantity bondQuantity(const pipeline::BondsDescription& bonds);

// The labelled values of a scalar bar over `range`: round numbers (1, 2 or
// 5 times a power of ten apart, about `count` of them), and the printf
// format that shows them exactly, without a trailing point ("199", not
// "199.") and as whole numbers for an integral quantity.
struct LegendTicks {
  std::vector<double> values;
  std::string format;
};
LegendTicks legendTicks(ValueRange range, bool integral, int count = 5);
std::string formatTick(const LegendTicks& ticks, double value);

// A legend's title broken at spaces into lines of at most `maxChars` (a word
// longer than that stands on a line of its own), so that it stays within
// the legend strip instead of running off the picture.
std::string wrapTitle(const std::string& title, std::size_t maxChars);

// A length scale bar: the round length (1, 2 or 5 times a power of ten
// metres) drawn at most `maxPixels` long where one pixel is `metresPerPixel`
// at the focal plane, and its label ("2 mm", "50 µm", "1 m").
struct ScaleBar {
  double metres = 0.0;
  double pixels = 0.0;
  std::string label;
};
ScaleBar scaleBar(double metresPerPixel, double maxPixels);

// The annotation lines: "step 120 of 0..199   t = 1.2e-03 s" and the crack
// method with its options (empty when hidden).
std::string stepAnnotation(const SceneInput& input);
std::string methodAnnotation(const pipeline::CracksDescription& cracks);

// A layer's colour range: the user's, the series' (when scanned), else the
// range of the values shown (`values`; an empty one widens to one unit).
ValueRange colourRange(const pipeline::ColourRange& range, const std::optional<ValueRange>& series,
                       ValueRange values);

// The primitives of `mesh` that `keep(k)` selects (k in VTK order: vertices,
// lines, polygons, volume cells), with their cell data; points are shared.
cracks::CrackMesh selectPrimitives(const cracks::CrackMesh& mesh,
                                   const std::function<bool(std::size_t)>& keep);

// The crack mesh split into the layers drawn differently: cracks (broken,
// consistent bonds, within the description's threshold), inconsistency marks
// (local Voronoi) and intact faces (the local decomposition). A layer the
// description does not show is empty.
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

// The bonds drawn (all or only broken ones, within the threshold) and the
// value each is coloured by.
struct BondLines {
  std::vector<dem::BondIndex> bonds;
  std::vector<double> values;
};
BondLines bondLines(const pipeline::BondsDescription& bonds, const SceneInput& input);
// A bond's value of a bond quantity (state: 1 broken, 0 intact).
double bondValue(pipeline::BondColourBy by, std::size_t bond, const SceneInput& input);

}  // namespace crackvis::scene
