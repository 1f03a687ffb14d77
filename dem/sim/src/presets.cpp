#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>

#include <crackvis/dem/lattice_generator.hpp>
#include <crackvis/sim/presets.hpp>

namespace crackvis::sim {
namespace {

using dem::Vec3;

// Full-size lattices of chapter 3.1.
constexpr int kPlateSitesPerRow = 120;
constexpr int kPlateRows = 39;
constexpr double kPlateRadius = 1.58e-3;
constexpr double kPlatePull = 0.05;
constexpr int kPlateSavedSteps = 1284;
constexpr int kPlateDefectBonds = 3;

constexpr int kCuboidLayers = 75;
constexpr int kCuboidSitesPerAxis = 25;
constexpr double kCuboidRadius = 2.0e-3;
constexpr double kCuboidPull = 0.025;
constexpr int kCuboidSavedSteps = 200;

// Simulated time of the last saved step (calibrated, docs/simulator.md).
constexpr double kPlateDuration = 3.0e-3;
constexpr double kCuboidDuration = 0.72e-3;
// Grips accelerate over about three times the time a longitudinal wave takes
// to cross the specimen (c ~ 1.4 sqrt(E / rho) ~ 4,900 m/s for the lattices
// here: 43 us for the cuboid, 80 us for the plate).
constexpr double kPlateRampTime = 0.25e-3;
constexpr double kCuboidRampTime = 0.13e-3;

// Clamped zones: this many site layers at each end along x.
constexpr int kClampLayers = 2;

// Defect rectangles of sets A, B, C on the grid of bond midpoints across the
// middle layer gap (49 x 49 midpoints at full size): width along y (centred)
// and depth from the bottom face, as fractions of the 49.
struct DefectShape {
  double width;
  double depth;
};
constexpr DefectShape kDefectA{25.0 / 49.0, 5.0 / 49.0};
constexpr DefectShape kDefectB{49.0 / 49.0, 5.0 / 49.0};
constexpr DefectShape kDefectC{11.0 / 49.0, 11.0 / 49.0};

int scaledCount(int full, double scale, int minimum) {
  return std::max(minimum, static_cast<int>(std::lround(full * scale)));
}

struct Geometry {
  int dimension = 3;
  double radius = 0.0;
  double layerSpacing = 0.0;  // along x, between clamp layers
  std::vector<Vec3> positions;
};

Geometry plateGeometry(double scale) {
  Geometry g;
  g.dimension = 2;
  g.radius = kPlateRadius / scale;
  const double d = 2.0 * g.radius;
  const double rowSpacing = d * std::sqrt(3.0) / 2.0;
  const int perRow = scaledCount(kPlateSitesPerRow, scale, 8);
  const int rows = scaledCount(kPlateRows, scale, 4);
  g.layerSpacing = d;
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < perRow; ++i) {
      g.positions.push_back({g.radius + i * d + (j % 2) * 0.5 * d, g.radius + j * rowSpacing, 0.0});
    }
  }
  return g;
}

// FCC with x along [100]: square layers (spacing d along y and z) d/sqrt(2)
// apart, every other layer shifted by (d/2, d/2). Each sphere touches 4 in its
// layer and 4 in each neighbouring layer.
Geometry cuboidGeometry(double scale) {
  Geometry g;
  g.dimension = 3;
  g.radius = kCuboidRadius / scale;
  const double d = 2.0 * g.radius;
  const int layers = scaledCount(kCuboidLayers, scale, 9);
  const int perAxis = scaledCount(kCuboidSitesPerAxis, scale, 3);
  g.layerSpacing = d / std::sqrt(2.0);
  for (int k = 0; k < perAxis; ++k) {
    for (int j = 0; j < perAxis; ++j) {
      for (int p = 0; p < layers; ++p) {
        const double shift = (p % 2) * 0.5 * d;
        g.positions.push_back(
            {g.radius + p * g.layerSpacing, g.radius + j * d + shift, g.radius + k * d + shift});
      }
    }
  }
  return g;
}

Vec3 midpoint(const std::vector<Vec3>& positions, dem::Bond bond) {
  return 0.5 * (positions[static_cast<std::size_t>(bond.first)] +
                positions[static_cast<std::size_t>(bond.second)]);
}

// Bonds whose ends lie on both sides of the plane x = cut.
std::vector<std::size_t> bondsCrossing(const Geometry& g, const std::vector<dem::Bond>& bonds,
                                       double cut) {
  std::vector<std::size_t> crossing;
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    const double a = g.positions[static_cast<std::size_t>(bonds[b].first)].x - cut;
    const double c = g.positions[static_cast<std::size_t>(bonds[b].second)].x - cut;
    if (a * c < 0.0) {
      crossing.push_back(b);
    }
  }
  return crossing;
}

// 2D: the `count` bonds across the vertical mid-line nearest the lower edge.
std::vector<std::size_t> plateDefect(const Geometry& g, const std::vector<dem::Bond>& bonds,
                                     int count) {
  const auto [lo, hi] = dem::boundingBox(g.positions);
  const double cut = 0.5 * (lo.x + hi.x);
  std::vector<std::size_t> crossing = bondsCrossing(g, bonds, cut);
  std::stable_sort(crossing.begin(), crossing.end(), [&](std::size_t a, std::size_t b) {
    return midpoint(g.positions, bonds[a]).y < midpoint(g.positions, bonds[b]).y;
  });
  crossing.resize(std::min(crossing.size(), static_cast<std::size_t>(count)));
  return crossing;
}

// Ranks of coordinates on a grid of quarter diameters (midpoints of bonds
// across a layer gap lie on it).
std::map<long, int> gridRanks(const std::vector<double>& values, double step) {
  std::map<long, int> ranks;
  for (double v : values) {
    ranks.emplace(std::lround(v / step), 0);
  }
  int rank = 0;
  for (auto& [key, value] : ranks) {
    value = rank++;
  }
  return ranks;
}

// 3D: a rectangle of the bonds across the middle layer gap, centred in y and
// reaching up from the bottom face (z minimum).
std::vector<std::size_t> cuboidDefect(const Geometry& g, const std::vector<dem::Bond>& bonds,
                                      DefectShape shape) {
  const auto [lo, hi] = dem::boundingBox(g.positions);
  const double x0 = lo.x;
  const int layers = static_cast<int>(std::lround((hi.x - x0) / g.layerSpacing)) + 1;
  const double cut = x0 + ((layers - 1) / 2 + 0.5) * g.layerSpacing;
  const std::vector<std::size_t> crossing = bondsCrossing(g, bonds, cut);
  std::vector<double> ys;
  std::vector<double> zs;
  for (std::size_t b : crossing) {
    ys.push_back(midpoint(g.positions, bonds[b]).y);
    zs.push_back(midpoint(g.positions, bonds[b]).z);
  }
  const double step = 0.5 * g.radius;
  const auto yRanks = gridRanks(ys, step);
  const auto zRanks = gridRanks(zs, step);
  const int ny = static_cast<int>(yRanks.size());
  const int nz = static_cast<int>(zRanks.size());
  const int width = std::clamp(static_cast<int>(std::lround(shape.width * ny)), 1, ny);
  const int depth = std::clamp(static_cast<int>(std::lround(shape.depth * nz)), 1, nz);
  const int yFirst = (ny - width) / 2;
  std::vector<std::size_t> defect;
  for (std::size_t k = 0; k < crossing.size(); ++k) {
    const int y = yRanks.at(std::lround(ys[k] / step));
    const int z = zRanks.at(std::lround(zs[k] / step));
    if (y >= yFirst && y < yFirst + width && z < depth) {
      defect.push_back(crossing[k]);
    }
  }
  return defect;
}

// Lattice stiffness from E: FCC with nearest-neighbour central springs has
// E_[100] = 4 k / (3 sqrt(2) d); a triangular lattice of thickness t = d has
// E t = 2 k / sqrt(3). Both give Poisson's ratio 1/3.
double bondStiffnessFor(int dimension, double youngsModulus, double radius) {
  const double d = 2.0 * radius;
  return dimension == 3 ? 3.0 * std::sqrt(2.0) / 4.0 * youngsModulus * d
                        : std::sqrt(3.0) / 2.0 * youngsModulus * d;
}

// Grips prescribe the velocity along x only and let the ends contract
// sideways: fully rigid grips concentrate stress at their edges (the Poisson
// contraction is blocked there) and the first bonds then break at the grips
// instead of at the defect (docs/simulator.md).
void clampEnds(SimulationSetup& setup, double reach, double velocity) {
  const auto [lo, hi] = dem::boundingBox(setup.positions);
  setup.clamped.assign(setup.positions.size(), 0);
  setup.prescribedVelocity.assign(setup.positions.size(), Vec3{});
  for (std::size_t p = 0; p < setup.positions.size(); ++p) {
    if (setup.positions[p].x < lo.x + reach) {
      setup.clamped[p] = kClampX;
      setup.prescribedVelocity[p] = {-velocity, 0.0, 0.0};
    } else if (setup.positions[p].x > hi.x - reach) {
      setup.clamped[p] = kClampX;
      setup.prescribedVelocity[p] = {velocity, 0.0, 0.0};
    }
  }
}

// More integration steps between two saves than any run finishes (at the
// cuboid's ~1 microsecond a step, 1e8 steps a save is days per saved step).
constexpr double kMaxStepsPerSave = 1e8;

// Whole steps between saves, the time step no larger than the stable one,
// and the last of `fullSaved` saved steps exactly at `duration`.
Status scheduleSteps(Preset& preset, const MaterialModel& model, double duration, int fullSaved,
                     int savedSteps) {
  SimulationSetup& setup = preset.setup;
  const double maxStep = model.timeStepFraction * bondTimeScale(setup.lattice, setup.material);
  const double interval = duration / (fullSaved - 1);
  const double perSave = std::ceil(interval / maxStep);
  if (!(perSave <= kMaxStepsPerSave)) {
    return invalidArgument(fmt::format(
        "a duration of {:g} s needs {:.3g} time steps of at most {:.3g} s between two saved steps; "
        "more than {:g} cannot finish (give a shorter --duration)",
        duration, perSave, maxStep, kMaxStepsPerSave));
  }
  preset.stepsPerSave = std::max<std::int64_t>(1, static_cast<std::int64_t>(perSave));
  setup.timeStep = interval / static_cast<double>(preset.stepsPerSave);
  preset.savedSteps = savedSteps > 0 ? savedSteps : fullSaved;
  return Status::ok();
}

// The material of a preset for bonds of typical radius r.
void applyMaterial(Material& material, const MaterialModel& model, int dimension, double radius) {
  material.density = model.density;
  material.bondStiffness = bondStiffnessFor(dimension, model.youngsModulus, radius);
  material.bondDamping = model.bondDamping;
  material.contact.effectiveModulus =
      model.youngsModulus / (2.0 * (1.0 - model.poissonRatio * model.poissonRatio));
  material.contact.restitution = model.restitution;
  material.contact.friction = model.friction;
}

Status validateMaterial(const MaterialModel& model) {
  CRACKVIS_RETURN_IF_ERROR(validate(model.strength));
  if (!(model.youngsModulus > 0.0) || !(model.density > 0.0) ||
      !(model.poissonRatio >= 0.0 && model.poissonRatio < 0.5) ||
      !(model.timeStepFraction > 0.0 && model.timeStepFraction <= 0.5)) {
    return invalidArgument(
        "material: E and density must be > 0, Poisson's ratio in [0, 0.5), time step fraction "
        "in (0, 0.5]");
  }
  return Status::ok();
}

}  // namespace

MaterialModel defaultMaterial(int dimension) {
  MaterialModel model;
  // 3D: a wide distribution, so that diffuse damage spreads from the main
  // crack; 2D: a higher threshold, so that the 3-bond defect (a weak stress
  // concentration) still breaks first (docs/simulator.md, "Calibration").
  model.strength = dimension == 3 ? StrengthDistribution{1.5e-5, 6.0e-5, 2.0}
                                  : StrengthDistribution{3.5e-5, 2.0e-5, 2.0};
  return model;
}

bool isPresetName(std::string_view name) {
  return name == "plate2d" || name == "cuboid3d";
}

double presetDuration(std::string_view name) {
  if (name == "plate2d") {
    return kPlateDuration;
  }
  return name == "cuboid3d" ? kCuboidDuration : 0.0;
}

Result<Preset> makePreset(const PresetOptions& options) {
  if (!isPresetName(options.name)) {
    return invalidArgument(
        fmt::format("unknown preset '{}' (expected plate2d or cuboid3d)", options.name));
  }
  if (!(options.scale > 0.0 && options.scale <= 1.0)) {
    return invalidArgument(fmt::format("scale must be in (0, 1], got {}", options.scale));
  }
  const bool plate = options.name == "plate2d";
  DefectShape shape = kDefectA;
  if (!plate) {
    switch (options.defectSet) {
      case 'A':
        shape = kDefectA;
        break;
      case 'B':
        shape = kDefectB;
        break;
      case 'C':
        shape = kDefectC;
        break;
      default:
        return invalidArgument(
            fmt::format("unknown defect set '{}' (expected A, B or C)", options.defectSet));
    }
  }
  if (options.savedSteps < 0 || options.duration < 0.0 || !std::isfinite(options.duration)) {
    return invalidArgument("saved steps and duration must not be negative");
  }
  const MaterialModel model =
      options.customMaterial ? options.material : defaultMaterial(plate ? 2 : 3);
  CRACKVIS_RETURN_IF_ERROR(validateMaterial(model));

  const Geometry g = plate ? plateGeometry(options.scale) : cuboidGeometry(options.scale);
  Preset preset;
  preset.description =
      plate ? fmt::format("plate2d, scale {}", options.scale)
            : fmt::format("cuboid3d set {}, scale {}", options.defectSet, options.scale);
  SimulationSetup& setup = preset.setup;
  dem::Lattice& lattice = setup.lattice;
  lattice.dimension = g.dimension;
  lattice.radius.assign(g.positions.size(), g.radius);
  lattice.bonds = dem::nearestNeighbourBonds(g.positions, g.radius);

  Material& material = setup.material;
  applyMaterial(material, model, g.dimension, g.radius);

  const std::vector<double> strains =
      drawBreakStrains(model.strength, lattice.bondCount(), options.seed);
  lattice.strength.resize(lattice.bondCount());
  for (std::size_t b = 0; b < lattice.bondCount(); ++b) {
    lattice.strength[b] = material.bondStiffness * 2.0 * g.radius * strains[b];
  }

  const std::vector<std::size_t> defect =
      plate ? plateDefect(g, lattice.bonds, scaledCount(kPlateDefectBonds, options.scale, 1))
            : cuboidDefect(g, lattice.bonds, shape);
  setup.bondState.assign(lattice.bondCount(), 0);
  Vec3 centre{};
  for (std::size_t b : defect) {
    setup.bondState[b] = static_cast<std::uint8_t>(dem::BondState::kBroken);
    centre = centre + midpoint(g.positions, lattice.bonds[b]);
  }
  preset.defectBonds = defect.size();
  preset.defectCentre =
      defect.empty() ? centre : (1.0 / static_cast<double>(defect.size())) * centre;

  const auto [lo, hi] = dem::boundingBox(g.positions);
  preset.extent = {hi.x - lo.x + 2.0 * g.radius, hi.y - lo.y + 2.0 * g.radius,
                   plate ? 0.0 : hi.z - lo.z + 2.0 * g.radius};
  preset.pullVelocity = plate ? kPlatePull : kCuboidPull;
  setup.positions = g.positions;
  clampEnds(setup, (kClampLayers - 0.25) * g.layerSpacing, preset.pullVelocity);
  setup.clampRampTime = plate ? kPlateRampTime : kCuboidRampTime;
  const double duration =
      options.duration > 0.0 ? options.duration : (plate ? kPlateDuration : kCuboidDuration);
  CRACKVIS_RETURN_IF_ERROR(scheduleSteps(
      preset, model, duration, plate ? kPlateSavedSteps : kCuboidSavedSteps, options.savedSteps));
  return preset;
}

Result<Preset> makeTensionPreset(const dem::Lattice& specimen,
                                 const std::vector<dem::Vec3>& positions,
                                 const PresetOptions& options, double notchDepth) {
  CRACKVIS_RETURN_IF_ERROR(dem::validateTopology(specimen));
  if (positions.size() != specimen.particleCount() || positions.size() < 2) {
    return invalidArgument(fmt::format("{} positions for N = {} particles", positions.size(),
                                       specimen.particleCount()));
  }
  if (!(notchDepth >= 0.0 && notchDepth < 1.0)) {
    return invalidArgument(fmt::format("notch depth {} is outside [0, 1)", notchDepth));
  }
  const int dimension = specimen.dimension;
  const MaterialModel model =
      options.customMaterial ? options.material : defaultMaterial(dimension);
  CRACKVIS_RETURN_IF_ERROR(validateMaterial(model));
  const bool plate = dimension == 2;
  double meanRadius = 0.0;
  for (double r : specimen.radius) {
    meanRadius += r / static_cast<double>(specimen.radius.size());
  }
  const auto [lo, hi] = dem::boundingBox(positions);
  const double length = hi.x - lo.x + 2.0 * meanRadius;

  Preset preset;
  preset.description = fmt::format("tension of a {}D specimen ({} particles, mean radius {:.4g} m)",
                                   dimension, positions.size(), meanRadius);
  SimulationSetup& setup = preset.setup;
  setup.lattice = specimen;
  setup.positions = positions;
  applyMaterial(setup.material, model, dimension, meanRadius);
  // Strength from each bond's rest length, so any packing breaks at the
  // strains the distribution gives.
  const std::vector<double> strains =
      drawBreakStrains(model.strength, specimen.bondCount(), options.seed);
  setup.lattice.strength.resize(specimen.bondCount());
  for (std::size_t b = 0; b < specimen.bondCount(); ++b) {
    const dem::Bond& bond = specimen.bonds[b];
    const double rest = dem::norm(positions[static_cast<std::size_t>(bond.second)] -
                                  positions[static_cast<std::size_t>(bond.first)]);
    setup.lattice.strength[b] = setup.material.bondStiffness * rest * strains[b];
  }
  // The notch: bonds across the mid-plane x from the bottom face (z in 3D,
  // y in 2D) up to notchDepth of the height, over the whole width.
  const double cut = 0.5 * (lo.x + hi.x);
  const int up = plate ? 1 : 2;
  const double bottom = dem::component(lo, up);
  const double height = dem::component(hi, up) - bottom;
  setup.bondState.assign(specimen.bondCount(), 0);
  Vec3 centre{};
  for (std::size_t b = 0; b < specimen.bondCount(); ++b) {
    const Vec3 a = positions[static_cast<std::size_t>(specimen.bonds[b].first)];
    const Vec3 c = positions[static_cast<std::size_t>(specimen.bonds[b].second)];
    const Vec3 middle = 0.5 * (a + c);
    if ((a.x - cut) * (c.x - cut) < 0.0 &&
        dem::component(middle, up) - bottom <= notchDepth * height) {
      setup.bondState[b] = static_cast<std::uint8_t>(dem::BondState::kBroken);
      centre = centre + middle;
      ++preset.defectBonds;
    }
  }
  preset.defectCentre =
      preset.defectBonds == 0 ? centre : (1.0 / static_cast<double>(preset.defectBonds)) * centre;
  preset.extent = {length, hi.y - lo.y + 2.0 * meanRadius,
                   plate ? 0.0 : hi.z - lo.z + 2.0 * meanRadius};
  // The benchmark's strain rate and loading time, scaled by the length: the
  // same strain history as the cuboid (the plate in 2D).
  const double referenceLength =
      plate ? kPlateSitesPerRow * 2.0 * kPlateRadius
            : (kCuboidLayers - 1) * 2.0 * kCuboidRadius / std::sqrt(2.0) + 2.0 * kCuboidRadius;
  const double referencePull = plate ? kPlatePull : kCuboidPull;
  preset.pullVelocity = referencePull * length / referenceLength;
  clampEnds(setup, 3.0 * meanRadius, preset.pullVelocity);
  setup.clampRampTime = (plate ? kPlateRampTime : kCuboidRampTime) * length / referenceLength;
  const double duration =
      options.duration > 0.0 ? options.duration : (plate ? kPlateDuration : kCuboidDuration);
  CRACKVIS_RETURN_IF_ERROR(
      scheduleSteps(preset, model, duration, kCuboidSavedSteps, options.savedSteps));
  return preset;
}

}  // namespace crackvis::sim
