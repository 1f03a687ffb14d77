#include <algorithm>
#include <cmath>
#include <cstdio>

#include <fmt/format.h>

#include <crackvis/analysis/fragments.hpp>
#include <crackvis/cracks/lattice_cells.hpp>
#include <crackvis/scene_model/scene_content.hpp>

namespace crackvis::scene {
namespace {

// A flag of primitive k from a cell array (absent array: `otherwise`).
bool flagOf(const cracks::AttributeArray* array, std::size_t k, bool otherwise) {
  if (array == nullptr || k >= array->values.size()) {
    return otherwise;
  }
  return array->values[k] != 0.0;
}

}  // namespace

// In FCC the third layer shows through the gaps of the first two along
// <111>, hence three layers. Deeper particles are hidden; impostors write
// their depth, so the GPU's early depth test cannot skip them and every
// hidden sphere would cost its fragments.
std::vector<dem::ParticleIndex> visibleParticles(const pipeline::ParticlesDescription& particles,
                                                 const SceneInput& input) {
  const std::size_t n = input.step.positions.size();
  const auto& bonds = input.lattice->bonds;
  std::vector<std::uint8_t> keep(n, 1);
  if (!(particles.opacity < 1.0 || particles.clip || particles.threshold || bonds.empty() ||
        input.step.bondState.size() != bonds.size())) {
    std::vector<int> degree(n, 0);
    std::fill(keep.begin(), keep.end(), 0);
    for (std::size_t b = 0; b < bonds.size(); ++b) {
      const auto i = static_cast<std::size_t>(bonds[b].first);
      const auto j = static_cast<std::size_t>(bonds[b].second);
      ++degree[i];
      ++degree[j];
      if (input.step.bondState[b] != 0) {
        keep[i] = keep[j] = 1;
      }
    }
    const int most = n > 0 ? *std::max_element(degree.begin(), degree.end()) : 0;
    for (std::size_t i = 0; i < n; ++i) {
      keep[i] = keep[i] != 0 || degree[i] < most ? 1 : 0;
    }
    for (std::uint8_t layer = 2; layer <= 3; ++layer) {
      for (const dem::Bond& bond : bonds) {
        auto& a = keep[static_cast<std::size_t>(bond.first)];
        auto& c = keep[static_cast<std::size_t>(bond.second)];
        if (a != 0 && a < layer && c == 0) {
          c = layer;
        } else if (c != 0 && c < layer && a == 0) {
          a = layer;
        }
      }
    }
  }
  std::vector<double> thresholded;
  if (particles.threshold) {
    thresholded = particleValues(particles.threshold->by, input);
  }
  std::vector<dem::ParticleIndex> visible;
  for (std::size_t i = 0; i < n; ++i) {
    if (keep[i] != 0 && (thresholded.empty() || particles.threshold->contains(thresholded[i]))) {
      visible.push_back(static_cast<dem::ParticleIndex>(i));
    }
  }
  return visible;
}

std::vector<double> particleValues(const pipeline::ParticlesDescription& particles,
                                   const SceneInput& input) {
  return particleValues(particles.colourBy, input);
}

std::vector<double> particleValues(pipeline::ParticleColourBy by, const SceneInput& input) {
  const std::size_t n = input.step.positions.size();
  std::vector<double> values(n, 0.0);
  switch (by) {
    case pipeline::ParticleColourBy::kRadius:
      std::copy_n(input.step.radius.begin(), std::min(n, input.step.radius.size()), values.begin());
      break;
    case pipeline::ParticleColourBy::kDisplacement:
      for (std::size_t i = 0; i < n && i < input.initialPositions.size(); ++i) {
        values[i] = dem::norm(input.step.positions[i] - input.initialPositions[i]);
      }
      break;
    case pipeline::ParticleColourBy::kVelocity:
      for (std::size_t i = 0; i < n && i < input.velocities.size(); ++i) {
        const auto& v = input.velocities[i];
        values[i] = std::sqrt(double{v[0]} * v[0] + double{v[1]} * v[1] + double{v[2]} * v[2]);
      }
      break;
    case pipeline::ParticleColourBy::kDamage: {
      std::vector<int> bonds(n, 0);
      std::vector<int> broken(n, 0);
      for (std::size_t b = 0; b < input.lattice->bonds.size(); ++b) {
        for (auto end : {input.lattice->bonds[b].first, input.lattice->bonds[b].second}) {
          ++bonds[static_cast<std::size_t>(end)];
          broken[static_cast<std::size_t>(end)] += input.step.bondState[b] != 0 ? 1 : 0;
        }
      }
      for (std::size_t i = 0; i < n; ++i) {
        values[i] = bonds[i] > 0 ? static_cast<double>(broken[i]) / bonds[i] : 0.0;
      }
      break;
    }
    case pipeline::ParticleColourBy::kExtra:
      std::copy_n(input.particleExtra.begin(), std::min(n, input.particleExtra.size()),
                  values.begin());
      break;
    case pipeline::ParticleColourBy::kFragment: {
      const analysis::Fragments fragments = analysis::findFragments(
          input.lattice->bonds, input.step.bondState, input.step.radius, input.lattice->dimension);
      const std::vector<double> labels = analysis::fragmentLabels(fragments, 1);
      std::copy_n(labels.begin(), std::min(n, labels.size()), values.begin());
      break;
    }
    case pipeline::ParticleColourBy::kSolid:
      break;
  }
  return values;
}

cracks::CrackMesh selectPrimitives(const cracks::CrackMesh& mesh,
                                   const std::function<bool(std::size_t)>& keep) {
  cracks::CrackMesh out;
  out.dimension = mesh.dimension;
  out.points = mesh.points;
  out.pointData = mesh.pointData;
  std::vector<std::size_t> kept;
  std::size_t k = 0;
  for (std::int32_t v : mesh.vertices) {
    if (keep(k)) {
      out.vertices.push_back(v);
      kept.push_back(k);
    }
    ++k;
  }
  auto copyList = [&](const cracks::PrimitiveList& from, cracks::PrimitiveList& to,
                      const std::vector<std::uint8_t>* types) {
    for (std::size_t i = 0; i < from.size(); ++i, ++k) {
      if (!keep(k)) {
        continue;
      }
      to.addRange(from.connectivity.begin() + from.offsets[i],
                  from.connectivity.begin() + from.offsets[i + 1]);
      if (types != nullptr) {
        out.volumeCellTypes.push_back((*types)[i]);
      }
      kept.push_back(k);
    }
  };
  copyList(mesh.lines, out.lines, nullptr);
  copyList(mesh.polygons, out.polygons, nullptr);
  copyList(mesh.volumeCells, out.volumeCells, &mesh.volumeCellTypes);
  for (const cracks::AttributeArray& array : mesh.cellData) {
    cracks::AttributeArray selected{array.name, array.type, array.components, {}};
    const auto c = static_cast<std::size_t>(array.components);
    for (std::size_t i : kept) {
      selected.values.insert(selected.values.end(), array.values.begin() + i * c,
                             array.values.begin() + (i + 1) * c);
    }
    out.cellData.push_back(std::move(selected));
  }
  return out;
}

CrackLayers crackLayers(const pipeline::PipelineDescription& d, const cracks::CrackMesh& mesh) {
  const cracks::AttributeArray* state = mesh.findCellData("bond_state");
  const cracks::AttributeArray* inconsistent = mesh.findCellData("inconsistent");
  const auto& threshold = d.cracks.threshold;
  const cracks::AttributeArray* thresholded =
      threshold ? mesh.findCellData(crackArrayName(threshold->by, d.cracks.method)) : nullptr;
  const auto within = [&](std::size_t k) {
    return thresholded == nullptr || k >= thresholded->values.size() ||
           threshold->contains(thresholded->values[k]);
  };
  CrackLayers layers;
  layers.cracks = selectPrimitives(mesh, [&](std::size_t k) {
    return flagOf(state, k, true) && !flagOf(inconsistent, k, false) && within(k);
  });
  if (d.showInconsistent && inconsistent != nullptr) {
    layers.marks =
        selectPrimitives(mesh, [&](std::size_t k) { return flagOf(inconsistent, k, false); });
  }
  if (d.showDecomposition && state != nullptr) {
    layers.intact = selectPrimitives(mesh, [&](std::size_t k) {
      return !flagOf(state, k, true) && !flagOf(inconsistent, k, false);
    });
  }
  return layers;
}

std::vector<dem::BondIndex> decompositionBonds(const SceneInput& input) {
  if (input.decomposition == nullptr) {
    return {};
  }
  const cracks::LatticeDecomposition& decomposition = *input.decomposition;
  std::vector<std::uint8_t> used(decomposition.graph().bondCount(), 0);
  for (const cracks::LatticeCell& cell : decomposition.cells()) {
    const auto& shape = cracks::shapeOf(cell.type);
    for (std::size_t e = 0; e < shape.edges.size(); ++e) {
      used[static_cast<std::size_t>(decomposition.bondOf(cell, static_cast<int>(e)))] = 1;
    }
  }
  std::vector<dem::BondIndex> bonds;
  for (std::size_t b = 0; b < used.size(); ++b) {
    if (used[b] != 0) {
      bonds.push_back(static_cast<dem::BondIndex>(b));
    }
  }
  return bonds;
}

double bondValue(pipeline::BondColourBy by, std::size_t b, const SceneInput& input) {
  switch (by) {
    case pipeline::BondColourBy::kForce:
      return b < input.step.bondForce.size() ? input.step.bondForce[b] : 0.0;
    case pipeline::BondColourBy::kBreakStep:
      return b < input.step.breakStep.size() ? input.step.breakStep[b] : 0.0;
    case pipeline::BondColourBy::kExtra:
      return b < input.bondExtra.size() ? input.bondExtra[b] : 0.0;
    case pipeline::BondColourBy::kState:
    case pipeline::BondColourBy::kSolid:
      break;
  }
  return input.step.bondState[b] != 0 ? 1.0 : 0.0;
}

BondLines bondLines(const pipeline::BondsDescription& d, const SceneInput& input) {
  BondLines lines;
  if (d.show == pipeline::BondSelection::kNone) {
    return lines;
  }
  for (std::size_t b = 0; b < input.lattice->bonds.size(); ++b) {
    const bool broken = input.step.bondState[b] != 0;
    if (d.show == pipeline::BondSelection::kBroken && !broken) {
      continue;
    }
    if (d.threshold && !d.threshold->contains(bondValue(d.threshold->by, b, input))) {
      continue;
    }
    lines.bonds.push_back(static_cast<dem::BondIndex>(b));
    lines.values.push_back(bondValue(d.colourBy, b, input));
  }
  return lines;
}

const char* crackArrayName(pipeline::CrackColourBy by, cracks::Method method) {
  if (method == cracks::Method::kCellAttribute) {
    if (by == pipeline::CrackColourBy::kBondId) {
      return "first_broken_bond";
    }
    if (by == pipeline::CrackColourBy::kState) {
      return "broken_bonds";
    }
  }
  switch (by) {
    case pipeline::CrackColourBy::kBondId:
      return "bond_id";
    case pipeline::CrackColourBy::kForce:
      return "bond_force";
    case pipeline::CrackColourBy::kBreakStep:
      return "break_step";
    case pipeline::CrackColourBy::kState:
      return "bond_state";
    case pipeline::CrackColourBy::kComponent:
      return "component";
    case pipeline::CrackColourBy::kOpening:
      return "opening";
    case pipeline::CrackColourBy::kSlip:
      return "slip";
    case pipeline::CrackColourBy::kSolid:
      break;
  }
  return nullptr;
}

Quantity particleQuantity(const pipeline::ParticlesDescription& particles) {
  switch (particles.colourBy) {
    case pipeline::ParticleColourBy::kRadius:
      return {"radius [m]"};
    case pipeline::ParticleColourBy::kDisplacement:
      return {"displacement [m]"};
    case pipeline::ParticleColourBy::kVelocity:
      return {"velocity [m/s]"};
    case pipeline::ParticleColourBy::kDamage:
      return {"damage (broken bond share)"};
    case pipeline::ParticleColourBy::kExtra:
      return {particles.colourByExtra};  // the file names no unit
    case pipeline::ParticleColourBy::kFragment:
      return {"fragment (0 largest)", true};
    case pipeline::ParticleColourBy::kSolid:
      break;
  }
  return {};
}

Quantity crackQuantity(pipeline::CrackColourBy by, cracks::Method method) {
  if (method == cracks::Method::kCellAttribute) {
    switch (by) {
      case pipeline::CrackColourBy::kBondId:
        return {"cell: first broken bond", true};
      case pipeline::CrackColourBy::kForce:
        return {"cell: largest bond force [N]"};
      case pipeline::CrackColourBy::kBreakStep:
        return {"cell: first break step", true};
      case pipeline::CrackColourBy::kState:
        return {"cell: broken bonds", true};
      default:
        break;
    }
  }
  switch (by) {
    case pipeline::CrackColourBy::kBondId:
      return {"bond id", true};
    case pipeline::CrackColourBy::kForce:
      return {"bond force [N]"};
    case pipeline::CrackColourBy::kBreakStep:
      return {"crack: break step", true};
    case pipeline::CrackColourBy::kState:
      return {"bond state (1 broken)", true};
    case pipeline::CrackColourBy::kComponent:
      return {"crack component (0 largest)", true};
    case pipeline::CrackColourBy::kOpening:
      return {"crack opening [m]"};
    case pipeline::CrackColourBy::kSlip:
      return {"crack slip [m]"};
    case pipeline::CrackColourBy::kSolid:
      break;
  }
  return {};
}

Quantity bondQuantity(const pipeline::BondsDescription& bonds) {
  switch (bonds.colourBy) {
    case pipeline::BondColourBy::kForce:
      return {"bond force [N]"};
    case pipeline::BondColourBy::kBreakStep:
      return {"bonds: break step", true};
    case pipeline::BondColourBy::kExtra:
      return {"bonds: " + bonds.colourByExtra};
    case pipeline::BondColourBy::kState:
      return {"bond state (1 broken)", true};
    case pipeline::BondColourBy::kSolid:
      break;
  }
  return {};
}

namespace {

// 1, 2 or 5 times a power of ten: the round number nearest above `x` > 0.
double roundUp(double x) {
  const double power = std::pow(10.0, std::floor(std::log10(x)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * power >= x * (1 - 1e-9)) {
      return m * power;
    }
  }
  return 10.0 * power;
}

// ... and nearest below.
double roundDown(double x) {
  const double power = std::pow(10.0, std::floor(std::log10(x)));
  for (double m : {5.0, 2.0, 1.0}) {
    if (m * power <= x * (1 + 1e-9)) {
      return m * power;
    }
  }
  return power;
}

}  // namespace

LegendTicks legendTicks(ValueRange range, bool integral, int count) {
  LegendTicks ticks;
  const double span = range.max - range.min;
  if (!(span > 0.0) || !std::isfinite(span)) {
    ticks.values = {range.min};
    ticks.format = integral ? "%.0f" : "%.4g";
    return ticks;
  }
  double step = roundUp(span / std::max(1, count - 1));
  if (integral) {
    step = std::max(step, 1.0);
  }
  const double first = std::ceil(range.min / step - 1e-9) * step;
  for (double v = first; v <= range.max + step * 1e-9; v += step) {
    // Multiples of the step, so 0.30000000000000004 prints as 0.3.
    // (+ 0.0 turns -0 into 0.)
    ticks.values.push_back(std::round(v / step) * step + 0.0);
  }
  if (integral) {
    ticks.format = "%.0f";
  } else {
    // Enough significant digits to tell neighbouring ticks apart, and to
    // write the largest without an exponent where that takes at most six.
    const double largest = std::max(std::abs(range.min), std::abs(range.max));
    const int magnitude = static_cast<int>(std::floor(std::log10(largest) + 1e-9));
    const int resolution = static_cast<int>(std::floor(std::log10(step) + 1e-9));
    const int digits = std::clamp(std::max(magnitude - resolution + 1, magnitude + 1), 1, 6);
    ticks.format = fmt::format("%.{}g", digits);
  }
  return ticks;
}

std::string formatTick(const LegendTicks& ticks, double value) {
  char text[64];
  std::snprintf(text, sizeof text, ticks.format.c_str(), value);
  return text;
}

std::string wrapTitle(const std::string& title, std::size_t maxChars) {
  std::string out;
  std::size_t lineLength = 0;
  std::size_t start = 0;
  while (start < title.size()) {
    std::size_t end = title.find(' ', start);
    end = end == std::string::npos ? title.size() : end;
    const std::size_t word = end - start;
    if (word > 0) {
      if (lineLength > 0 && lineLength + 1 + word > maxChars) {
        out += '\n';
        lineLength = 0;
      } else if (lineLength > 0) {
        out += ' ';
        ++lineLength;
      }
      out.append(title, start, word);
      lineLength += word;
    }
    start = end + 1;
  }
  return out;
}

ScaleBar scaleBar(double metresPerPixel, double maxPixels) {
  ScaleBar bar;
  if (!(metresPerPixel > 0.0) || !(maxPixels > 0.0) || !std::isfinite(metresPerPixel)) {
    return bar;
  }
  bar.metres = roundDown(metresPerPixel * maxPixels);
  bar.pixels = bar.metres / metresPerPixel;
  struct Unit {
    double size;
    const char* name;
  };
  static constexpr Unit kUnits[] = {
      {1e3, "km"}, {1.0, "m"}, {1e-3, "mm"}, {1e-6, "µm"}, {1e-9, "nm"}};
  for (const Unit& unit : kUnits) {
    if (bar.metres >= unit.size * (1 - 1e-9) || unit.size == 1e-9) {
      bar.label = fmt::format("{:g} {}", bar.metres / unit.size, unit.name);
      break;
    }
  }
  return bar;
}

std::string stepAnnotation(const SceneInput& input) {
  if (input.stepIndex < 0) {
    return {};
  }
  if (input.timeInIterations) {
    return fmt::format("step {} of 0..{}   iteration {:.12g}", input.stepIndex,
                       std::max(0, input.stepCount - 1), input.time);
  }
  return fmt::format("step {} of 0..{}   t = {:.4g} s", input.stepIndex,
                     std::max(0, input.stepCount - 1), input.time);
}

std::string methodAnnotation(const pipeline::CracksDescription& c) {
  if (!c.visible) {
    return {};
  }
  switch (c.method) {
    case cracks::Method::kCellAttribute:
      return "cracks: cell attribute";
    case cracks::Method::kCellCut:
      return "cracks: cell cut";
    case cracks::Method::kCellCentre:
      return c.mergeOctahedra ? "cracks: cell centre, octahedra merged" : "cracks: cell centre";
    case cracks::Method::kLocalVoronoi:
      return c.validation ? fmt::format("cracks: local Voronoi, validated (tolerance {:g})",
                                        c.validationTolerance)
                          : "cracks: local Voronoi, not validated";
  }
  return {};
}

ValueRange colourRange(const pipeline::ColourRange& range, const std::optional<ValueRange>& series,
                       ValueRange values) {
  ValueRange chosen = values;
  if (range.mode == pipeline::RangeMode::kUser) {
    chosen = {range.min, range.max};
  } else if (range.mode == pipeline::RangeMode::kSeries && series) {
    chosen = *series;
  }
  if (!(chosen.max > chosen.min)) {
    chosen.max = chosen.min + 1.0;
  }
  return chosen;
}

}  // namespace crackvis::scene
