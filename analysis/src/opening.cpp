#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <crackvis/analysis/bond_normals.hpp>
#include <crackvis/analysis/opening.hpp>
#include <crackvis/analysis/tensor.hpp>

namespace crackvis::analysis {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The first primitive of ofPrimitive's numbering among all primitives.
std::size_t surfaceBase(const CrackMesh& mesh) {
  return mesh.vertices.size() + (mesh.dimension == 2 ? 0 : mesh.lines.size());
}

// The bonds an element stands for: its cell's bond_id, or its points'.
template <typename Visit>
void forEachBond(const CrackMesh& mesh, const cracks::Primitive& primitive, std::size_t bondCount,
                 const cracks::AttributeArray* cellIds, const cracks::AttributeArray* pointIds,
                 Visit&& visit) {
  auto valid = [&](double id) { return id >= 0.0 && id < static_cast<double>(bondCount); };
  if (cellIds != nullptr) {
    const double id = cellIds->values[surfaceBase(mesh) + primitive.index];
    if (valid(id)) {
      visit(static_cast<std::size_t>(id));
    }
    return;
  }
  if (pointIds != nullptr) {
    for (std::size_t k = 0; k < primitive.count; ++k) {
      const double id = pointIds->values[static_cast<std::size_t>(primitive.ids[k])];
      if (valid(id)) {
        visit(static_cast<std::size_t>(id));
      }
    }
  }
}

Vec3 elementNormal(const CrackMesh& mesh, const cracks::Primitive& primitive) {
  if (mesh.dimension == 2) {
    const Vec3 d = mesh.points[static_cast<std::size_t>(primitive.ids[1])] -
                   mesh.points[static_cast<std::size_t>(primitive.ids[0])];
    const double length = std::hypot(d.x, d.y);
    return length > 0.0 ? Vec3{-d.y / length, d.x / length, 0.0} : Vec3{};
  }
  // polygonNormal is Newell's vector over 2, as long as the face's area:
  // the element's normal is a unit one, as a bond's is.
  const Vec3 n = cracks::polygonNormal(mesh.points, primitive.ids, primitive.count);
  const double length = dem::norm(n);
  return length > 0.0 ? (1.0 / length) * n : Vec3{};
}

// The bonds' part of element e of `out`: its cell, and the opening and slip
// of the bonds it stands for (NaN without one) along their normal (without
// one, the face's own).
void measureJump(const CrackMesh& mesh, const cracks::Primitive& primitive,
                 std::span<const dem::Bond> bonds, std::span<const Vec3> reference,
                 std::span<const Vec3> current, const BondNormals& normals,
                 const cracks::AttributeArray* cellIds, const cracks::AttributeArray* pointIds,
                 std::size_t base, ElementOpenings& out, std::size_t e) {
  out.cell[e] = base + primitive.index;
  out.opening[e] = kNaN;
  out.slip[e] = kNaN;
  // The bonds of one cell cut element may cross the crack either way
  // round: each counts along the first one's normal (the normals of
  // neighbouring bonds are nearly parallel; their axes need not be).
  Vec3 jump{};
  Vec3 firstNormal{};
  Vec3 normal{};
  int carried = 0;
  forEachBond(mesh, primitive, bonds.size(), cellIds, pointIds, [&](std::size_t b) {
    const auto i = static_cast<std::size_t>(bonds[b].first);
    const auto j = static_cast<std::size_t>(bonds[b].second);
    if (i >= reference.size() || j >= reference.size()) {
      return;
    }
    const Vec3 bondNormal = normals.normal(b);
    if (carried == 0) {
      firstNormal = bondNormal;
    }
    const double side = dem::dot(bondNormal, firstNormal) < 0.0 ? -1.0 : 1.0;
    jump = jump + side * (current[j] - current[i] - (reference[j] - reference[i]));
    normal = normal + side * bondNormal;
    ++carried;
  });
  const double length = dem::norm(normal);
  if (carried == 0 || length == 0.0) {
    // No bond: the face's own normal (orientation counts it still).
    out.normal[e] = elementNormal(mesh, primitive);
    return;
  }
  out.normal[e] = (1.0 / length) * normal;
  const Vec3 meanJump = (1.0 / carried) * jump;
  const double normalPart = dem::dot(meanJump, out.normal[e]);
  out.opening[e] = normalPart;
  out.slip[e] = dem::norm(meanJump - normalPart * out.normal[e]);
}

// Each element's arrays sized to `count`, keeping their memory.
void sizeElements(ElementOpenings& out, std::size_t count) {
  out.area.resize(count);
  out.centroid.resize(count);
  out.normal.resize(count);
  out.component.resize(count);
  out.cell.resize(count);
  out.opening.resize(count);
  out.slip.resize(count);
}

// Elements per block of the passes on all cores (each element on its own:
// the same figures on any number of cores).
constexpr std::size_t kElementBlock = 1024;

}  // namespace

void measureBondOpenings(const CrackMesh& mesh, std::span<const cracks::Primitive> primitives,
                         std::span<const dem::Bond> bonds, std::span<const Vec3> reference,
                         std::span<const Vec3> current, const BondNormals& normals,
                         ElementOpenings& out) {
  const cracks::AttributeArray* cellIds = mesh.findCellData("bond_id");
  const cracks::AttributeArray* pointIds = cellIds ? nullptr : mesh.findPointData("bond_id");
  const std::size_t n = std::min(reference.size(), current.size());
  out.smoothingRadius = normals.radius();
  sizeElements(out, primitives.size());
  const std::size_t base = surfaceBase(mesh);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, primitives.size(), kElementBlock),
                    [&](const auto& range) {
                      for (std::size_t e = range.begin(); e < range.end(); ++e) {
                        measureJump(mesh, primitives[e], bonds, reference.first(n),
                                    current.first(n), normals, cellIds, pointIds, base, out, e);
                      }
                    });
}

void placeOpenings(const CrackMesh& mesh, std::span<const cracks::Primitive> primitives,
                   const CrackComponents& components,
                   std::span<const cracks::PrimitiveExtent> extents, ElementOpenings& out) {
  if (extents.size() != primitives.size()) {
    extents = {};
  }
  sizeElements(out, primitives.size());  // nothing to do after measureBondOpenings
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, primitives.size(), kElementBlock),
                    [&](const auto& range) {
                      for (std::size_t e = range.begin(); e < range.end(); ++e) {
                        const cracks::Primitive& primitive = primitives[e];
                        const cracks::PrimitiveExtent shape =
                            extents.empty() ? cracks::measureExtent(mesh, primitive) : extents[e];
                        out.area[e] = shape.area;
                        out.centroid[e] = shape.centroid;
                        out.component[e] = primitive.index < components.ofPrimitive.size()
                                               ? components.ofPrimitive[primitive.index]
                                               : -1;
                      }
                    });
}

ElementOpenings measureOpening(const CrackMesh& mesh, const CrackComponents& components,
                               std::span<const dem::Bond> bonds, std::span<const Vec3> reference,
                               std::span<const Vec3> current, const OpeningOptions& options,
                               const BondNormals* normals) {
  const std::vector<cracks::Primitive> primitives = cracks::surfacePrimitives(mesh);
  // Without a caller's normals, those of the bonds this mesh carries.
  BondNormals own(mesh.dimension, options.smoothingRadius);
  if (normals == nullptr) {
    const cracks::AttributeArray* cellIds = mesh.findCellData("bond_id");
    const cracks::AttributeArray* pointIds = cellIds ? nullptr : mesh.findPointData("bond_id");
    std::vector<std::int32_t> carried;
    for (const cracks::Primitive& primitive : primitives) {
      forEachBond(mesh, primitive, bonds.size(), cellIds, pointIds,
                  [&](std::size_t b) { carried.push_back(static_cast<std::int32_t>(b)); });
    }
    own.add(bonds, carried, reference.first(std::min(reference.size(), current.size())));
    normals = &own;
  }
  ElementOpenings out;
  measureBondOpenings(mesh, primitives, bonds, reference, current, *normals, out);
  placeOpenings(mesh, primitives, components, {}, out);
  return out;
}

void appendOpeningArrays(CrackMesh& mesh, const ElementOpenings& openings) {
  const std::size_t cells = mesh.primitiveCount();
  std::vector<double> openingSum(cells, 0.0);
  std::vector<double> slipSum(cells, 0.0);
  std::vector<int> counted(cells, 0);
  // A 2D line's segments share its cell: the line takes their mean.
  for (std::size_t e = 0; e < openings.cell.size() && e < openings.size(); ++e) {
    const std::size_t cell = openings.cell[e];
    if (!std::isnan(openings.opening[e]) && cell < cells) {
      openingSum[cell] += openings.opening[e];
      slipSum[cell] += openings.slip[e];
      ++counted[cell];
    }
  }
  cracks::AttributeArray opening{"opening", cracks::AttributeType::kFloat64, 1, {}};
  cracks::AttributeArray slip{"slip", cracks::AttributeType::kFloat64, 1, {}};
  opening.values.assign(cells, kNaN);
  slip.values.assign(cells, kNaN);
  for (std::size_t cell = 0; cell < cells; ++cell) {
    if (counted[cell] > 0) {
      opening.values[cell] = openingSum[cell] / counted[cell];
      slip.values[cell] = slipSum[cell] / counted[cell];
    }
  }
  mesh.cellData.push_back(std::move(opening));
  mesh.cellData.push_back(std::move(slip));
}

namespace {

bool inComponent(const ElementOpenings& openings, std::size_t e, int component) {
  return !std::isnan(openings.opening[e]) && (component < 0 || openings.component[e] == component);
}

}  // namespace

namespace {

void accumulate(OpeningSummary& summary, const ElementOpenings& openings, std::size_t e) {
  const double a = openings.area[e];
  ++summary.elements;
  summary.area += a;
  summary.meanOpening += a * openings.opening[e];
  summary.meanSlip += a * openings.slip[e];
  summary.maxOpening = std::max(summary.maxOpening, openings.opening[e]);
  summary.maxSlip = std::max(summary.maxSlip, openings.slip[e]);
}

OpeningSummary finish(OpeningSummary summary) {
  if (summary.elements == 0) {
    return {};
  }
  if (summary.area > 0.0) {
    summary.meanOpening /= summary.area;
    summary.meanSlip /= summary.area;
  }
  return summary;
}

OpeningSummary started() {
  OpeningSummary summary;
  summary.maxOpening = -std::numeric_limits<double>::infinity();
  summary.maxSlip = -std::numeric_limits<double>::infinity();
  return summary;
}

}  // namespace

OpeningSummary summariseOpening(const ElementOpenings& openings, int component) {
  OpeningSummary summary = started();
  for (std::size_t e = 0; e < openings.size(); ++e) {
    if (inComponent(openings, e, component)) {
      accumulate(summary, openings, e);
    }
  }
  return finish(summary);
}

std::vector<OpeningSummary> summariseByComponent(const ElementOpenings& openings,
                                                 std::size_t components) {
  std::vector<OpeningSummary> summaries(components, started());
  for (std::size_t e = 0; e < openings.size(); ++e) {
    const int c = openings.component[e];
    if (!std::isnan(openings.opening[e]) && c >= 0 && static_cast<std::size_t>(c) < components) {
      accumulate(summaries[static_cast<std::size_t>(c)], openings, e);
    }
  }
  for (OpeningSummary& summary : summaries) {
    summary = finish(summary);
  }
  return summaries;
}

Histogram openingHistogram(const ElementOpenings& openings, int component, double lo, double hi,
                           int bins) {
  Histogram histogram{lo, hi, std::vector<double>(static_cast<std::size_t>(std::max(bins, 1)))};
  const double width = histogram.binWidth();
  for (std::size_t e = 0; e < openings.size(); ++e) {
    if (!inComponent(openings, e, component)) {
      continue;
    }
    const double at = width > 0.0 ? std::floor((openings.opening[e] - lo) / width) : 0.0;
    const auto bin = static_cast<std::size_t>(
        std::clamp(at, 0.0, static_cast<double>(histogram.weight.size() - 1)));
    histogram.weight[bin] += openings.area[e];
  }
  return histogram;
}

std::vector<ProfileBin> openingProfile(const ElementOpenings& openings, int component, Vec3 axis,
                                       int bins) {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  for (std::size_t e = 0; e < openings.size(); ++e) {
    if (inComponent(openings, e, component)) {
      const double s = dem::dot(openings.centroid[e], axis);
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    }
  }
  if (!(hi >= lo) || bins < 1) {
    return {};
  }
  const double width = hi > lo ? (hi - lo) / bins : 1.0;
  std::vector<ProfileBin> sums(static_cast<std::size_t>(bins));
  for (std::size_t e = 0; e < openings.size(); ++e) {
    if (!inComponent(openings, e, component)) {
      continue;
    }
    const double s = dem::dot(openings.centroid[e], axis);
    const auto k = static_cast<std::size_t>(
        std::clamp(std::floor((s - lo) / width), 0.0, static_cast<double>(bins - 1)));
    const double a = openings.area[e];
    sums[k].area += a;
    sums[k].opening += a * openings.opening[e];
    sums[k].slip += a * openings.slip[e];
  }
  std::vector<ProfileBin> profile;
  for (std::size_t k = 0; k < sums.size(); ++k) {
    if (sums[k].area > 0.0) {
      profile.push_back({lo + (static_cast<double>(k) + 0.5) * width, sums[k].area,
                         sums[k].opening / sums[k].area, sums[k].slip / sums[k].area});
    }
  }
  return profile;
}

Vec3 longestAxis(const ElementOpenings& openings, int component, Vec3 planeNormal) {
  double area = 0.0;
  Vec3 mean{};
  for (std::size_t e = 0; e < openings.size(); ++e) {
    if (component < 0 || openings.component[e] == component) {
      area += openings.area[e];
      mean = mean + openings.area[e] * openings.centroid[e];
    }
  }
  if (area <= 0.0) {
    return {};
  }
  mean = (1.0 / area) * mean;
  AxialTensor spread;
  for (std::size_t e = 0; e < openings.size(); ++e) {
    if (component < 0 || openings.component[e] == component) {
      Vec3 d = openings.centroid[e] - mean;
      d = d - dem::dot(d, planeNormal) * planeNormal;
      spread.add(d, openings.area[e]);
    }
  }
  return spread.principalAxis();
}

}  // namespace crackvis::analysis
