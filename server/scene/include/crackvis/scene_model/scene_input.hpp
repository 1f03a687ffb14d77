// What one step of a scene needs besides its pipeline description: the
// lattice, the step, the reference positions (step 0, for displacement), the
// extracted cracks and the cell methods' decomposition. Views only: the
// arrays belong to whoever made the input (a ScenePipeline, a test).
#pragma once

#include <array>
#include <optional>
#include <span>

#include <crackvis/cracks/extractor.hpp>

namespace crackvis::scene {

// A closed interval of values (a colour range).
struct ValueRange {
  double min = 0.0;
  double max = 0.0;
  friend bool operator==(const ValueRange&, const ValueRange&) = default;
};

// The ranges of the coloured quantities over every step of the file, for
// layers whose description asks for range="series".
struct SeriesRanges {
  std::optional<ValueRange> particles;
  std::optional<ValueRange> cracks;
  std::optional<ValueRange> bonds;
};

struct SceneInput {
  const dem::Lattice* lattice = nullptr;
  cracks::StepInput step;
  std::span<const dem::Vec3> initialPositions;       // may be empty
  std::span<const std::array<float, 3>> velocities;  // may be empty
  const cracks::CrackMesh* cracks = nullptr;         // may be null
  // The cell methods' decomposition, drawn as its edges when the description
  // shows the decomposition (local Voronoi shows its intact faces instead).
  const cracks::LatticeDecomposition* decomposition = nullptr;
  std::span<const float> particleExtra;  // [N] the extra array coloured by; may be empty
  std::span<const float> bondExtra;      // [M] likewise for the bonds
  SeriesRanges series;                   // scanned when a layer asks for it
  // For the annotations: the step shown (-1: unknown) of how many, and its time.
  int stepIndex = -1;
  int stepCount = 0;
  double time = 0.0;
  bool timeInIterations = false;  // `time` is the code's step number (no time was written)
};

}  // namespace crackvis::scene
