// What is drawn under a point of the view (a double click in the client):
// the nearest particle or crack element a ray from the eye meets, among
// those the description shows (visible layers, their clipping planes and
// thresholds), with the values a researcher asks of it. GL-free: the ray
// comes from the renderer's camera, the test is geometry (spheres with
// their radii; crack polygons and the cell attribute method's convex
// cells), so tests check it against analytic hits.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/scene_model/scene_input.hpp>

namespace crackvis::scene {

struct Ray {
  dem::Vec3 origin;
  dem::Vec3 direction;  // need not be unit length
};

struct PickedValue {
  std::string name;
  double value = 0.0;
  std::string unit;  // SI; empty for counts, ids and ratios
};

enum class PickedKind { kNothing, kParticle, kCrack };

struct PickResult {
  PickedKind kind = PickedKind::kNothing;
  std::int64_t index = -1;  // the particle, or the crack element (cell of the crack mesh)
  dem::Vec3 point;          // where the ray meets it, metres
  std::vector<PickedValue> values;
};

// The nearest shown particle or crack element along `ray` (only hits in
// front of its origin count).
PickResult pick(const pipeline::PipelineDescription& description, const SceneInput& input,
                const Ray& ray);

// "particle", "crack element", or "" for nothing.
const char* pickedKindName(PickedKind kind);

// "particle 120 at (0.01, 0.02, 0.03) m: radius 0.0005 m, damage 0.25, ..."
std::string describePick(const PickResult& result);

}  // namespace crackvis::scene
