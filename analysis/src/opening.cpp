#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <unordered_map>

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
  return cracks::polygonNormal(mesh.points, primitive.ids, primitive.count);
}

Vec3 centroidOf(const CrackMesh& mesh, const cracks::Primitive& primitive) {
  Vec3 sum{};
  for (std::size_t k = 0; k < primitive.count; ++k) {
    sum = sum + mesh.points[static_cast<std::size_t>(primitive.ids[k])];
  }
  return (1.0 / static_cast<double>(std::max<std::size_t>(primitive.count, 1))) * sum;
}

// Element centroids hashed in cubes of the smoothing radius.
class CentroidGrid {
 public:
  CentroidGrid(const std::vector<Vec3>& centroids, double cell) : m_cell(cell) {
    for (std::size_t e = 0; e < centroids.size(); ++e) {
      m_cells[key(cellOf(centroids[e]))].push_back(e);
    }
  }
  template <typename Visit>
  void forNear(Vec3 p, Visit&& visit) const {
    const std::array<std::int64_t, 3> c = cellOf(p);
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const auto found = m_cells.find(key({c[0] + dx, c[1] + dy, c[2] + dz}));
          if (found != m_cells.end()) {
            for (std::size_t e : found->second) {
              visit(e);
            }
          }
        }
      }
    }
  }

 private:
  std::array<std::int64_t, 3> cellOf(Vec3 p) const {
    return {static_cast<std::int64_t>(std::floor(p.x / m_cell)),
            static_cast<std::int64_t>(std::floor(p.y / m_cell)),
            static_cast<std::int64_t>(std::floor(p.z / m_cell))};
  }
  static std::uint64_t key(std::array<std::int64_t, 3> c) {
    const auto part = [](std::int64_t v) { return static_cast<std::uint64_t>(v) & 0x1FFFFFu; };
    return part(c[0]) | (part(c[1]) << 21) | (part(c[2]) << 42);
  }
  double m_cell;
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> m_cells;
};

// The normal of the local plane through the centroids of `near`: nullopt
// when they make no plane (too few, or spread in every direction alike).
std::optional<Vec3> centroidPlaneNormal(const ElementOpenings& out,
                                        const std::vector<std::size_t>& near,
                                        const std::vector<double>& kernel, bool flat) {
  if (near.size() < (flat ? 2u : 3u)) {
    return std::nullopt;
  }
  double weight = 0.0;
  Vec3 mean{};
  for (std::size_t k = 0; k < near.size(); ++k) {
    weight += kernel[k];
    mean = mean + kernel[k] * out.centroid[near[k]];
  }
  if (!(weight > 0.0)) {
    return std::nullopt;
  }
  mean = (1.0 / weight) * mean;
  AxialTensor spread;
  for (std::size_t k = 0; k < near.size(); ++k) {
    spread.add(out.centroid[near[k]] - mean, kernel[k]);
  }
  const double total = spread.trace();
  if (flat) {
    spread.addZ(total + 1.0);
  }
  const Vec3 normal = spread.smallestAxis();
  const double across = spread.along(normal);
  const double inPlane = flat ? total - across : (total - across) / 2.0;
  // A plane: far less spread across it than along it.
  if (!(across < 0.1 * inPlane)) {
    return std::nullopt;
  }
  return normal;
}

// The crack's local normals (see the header), in place of the elements' own:
// the plane through the centroids of the component's elements nearby (it
// stays true at the crack's edges, where the neighbourhood is one-sided), or
// where they make no plane, the mean axis of their bonds. Each neighbour
// weighs its area times (1 - (r/R)^2)^2: a lattice crack zig-zags, and
// neighbours that enter the window at its edge with full weight would tilt
// the plane by whichever half zig-zag they bring.
void smoothNormals(ElementOpenings& out, const std::vector<Vec3>& own, bool flat) {
  if (out.smoothingRadius <= 0.0) {
    return;
  }
  const CentroidGrid grid(out.centroid, out.smoothingRadius);
  const double r2 = out.smoothingRadius * out.smoothingRadius;
  std::vector<std::size_t> near;
  std::vector<double> kernel;
  for (std::size_t e = 0; e < out.size(); ++e) {
    if (out.component[e] < 0) {
      continue;
    }
    near.clear();
    kernel.clear();
    grid.forNear(out.centroid[e], [&](std::size_t f) {
      const Vec3 d = out.centroid[f] - out.centroid[e];
      const double q = dem::dot(d, d) / r2;
      if (out.component[f] == out.component[e] && q < 1.0) {
        near.push_back(f);
        kernel.push_back(out.area[f] * (1.0 - q) * (1.0 - q));
      }
    });
    Vec3 axis;
    if (const auto plane = centroidPlaneNormal(out, near, kernel, flat)) {
      axis = *plane;
    } else {
      AxialTensor bondAxes;
      for (std::size_t k = 0; k < near.size(); ++k) {
        bondAxes.add(own[near[k]], kernel[k]);
      }
      axis = bondAxes.principalAxis();
    }
    out.normal[e] = dem::dot(axis, own[e]) < 0.0 ? -1.0 * axis : axis;
  }
}

}  // namespace

ElementOpenings measureOpening(const CrackMesh& mesh, const CrackComponents& components,
                               std::span<const dem::Bond> bonds, std::span<const Vec3> reference,
                               std::span<const Vec3> current, const OpeningOptions& options) {
  const std::vector<cracks::Primitive> primitives = cracks::surfacePrimitives(mesh);
  const cracks::AttributeArray* cellIds = mesh.findCellData("bond_id");
  const cracks::AttributeArray* pointIds = cellIds ? nullptr : mesh.findPointData("bond_id");
  const std::size_t n = std::min(reference.size(), current.size());
  ElementOpenings out;
  const std::size_t count = primitives.size();
  out.area.resize(count);
  out.centroid.resize(count);
  out.normal.resize(count);
  out.component.assign(count, -1);
  std::vector<Vec3> jump(count);
  std::vector<Vec3> bondAxis(count);
  std::vector<int> carried(count, 0);
  double lengthSum = 0.0;
  std::size_t lengthCount = 0;
  for (std::size_t e = 0; e < count; ++e) {
    const cracks::Primitive& primitive = primitives[e];
    out.area[e] = cracks::measure(mesh, primitive);
    out.centroid[e] = centroidOf(mesh, primitive);
    out.normal[e] = elementNormal(mesh, primitive);
    if (primitive.index < components.ofPrimitive.size()) {
      out.component[e] = components.ofPrimitive[primitive.index];
    }
    forEachBond(mesh, primitive, bonds.size(), cellIds, pointIds, [&](std::size_t b) {
      const auto i = static_cast<std::size_t>(bonds[b].first);
      const auto j = static_cast<std::size_t>(bonds[b].second);
      if (i >= n || j >= n) {
        return;
      }
      const Vec3 d0 = reference[j] - reference[i];
      // The bonds of one cell cut element may be listed either way round:
      // each counts along the element's first bond.
      const double side = carried[e] > 0 && dem::dot(d0, bondAxis[e]) < 0.0 ? -1.0 : 1.0;
      jump[e] = jump[e] + side * (current[j] - current[i] - d0);
      bondAxis[e] = bondAxis[e] + side * d0;
      lengthSum += dem::norm(d0);
      ++lengthCount;
      ++carried[e];
    });
  }
  out.smoothingRadius = options.smoothingRadius > 0.0 ? options.smoothingRadius
                        : lengthCount > 0 ? 3.0 * lengthSum / static_cast<double>(lengthCount)
                                          : 0.0;
  // An element's own direction is its bonds' reference axis: a face's
  // normal in the current configuration leans over as the crack opens (the
  // cells that straddle the gap stretch), the bond it stands for does not;
  // local Voronoi's faces are normal to it in the reference.
  for (std::size_t e = 0; e < count; ++e) {
    const double length = dem::norm(bondAxis[e]);
    if (carried[e] > 0 && length > 0.0) {
      out.normal[e] = (1.0 / length) * bondAxis[e];
    }
  }
  const std::vector<Vec3> own = out.normal;
  smoothNormals(out, own, mesh.dimension == 2);
  out.opening.assign(count, kNaN);
  out.slip.assign(count, kNaN);
  for (std::size_t e = 0; e < count; ++e) {
    if (carried[e] == 0) {
      continue;
    }
    const Vec3 meanJump = (1.0 / carried[e]) * jump[e];
    const double normalPart = dem::dot(meanJump, out.normal[e]);
    out.opening[e] = normalPart;
    out.slip[e] = dem::norm(meanJump - normalPart * out.normal[e]);
  }
  return out;
}

void appendOpeningArrays(CrackMesh& mesh, const ElementOpenings& openings) {
  const std::vector<cracks::Primitive> primitives = cracks::surfacePrimitives(mesh);
  const std::size_t cells = mesh.primitiveCount();
  std::vector<double> openingSum(cells, 0.0);
  std::vector<double> slipSum(cells, 0.0);
  std::vector<int> counted(cells, 0);
  const std::size_t base = surfaceBase(mesh);
  // A 2D line's segments share its cell: the line takes their mean.
  for (std::size_t e = 0; e < primitives.size() && e < openings.size(); ++e) {
    if (!std::isnan(openings.opening[e])) {
      const std::size_t cell = base + primitives[e].index;
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

OpeningSummary summariseOpening(const ElementOpenings& openings, int component) {
  OpeningSummary summary;
  summary.maxOpening = -std::numeric_limits<double>::infinity();
  for (std::size_t e = 0; e < openings.size(); ++e) {
    if (!inComponent(openings, e, component)) {
      continue;
    }
    const double a = openings.area[e];
    ++summary.elements;
    summary.area += a;
    summary.meanOpening += a * openings.opening[e];
    summary.meanSlip += a * openings.slip[e];
    summary.maxOpening = std::max(summary.maxOpening, openings.opening[e]);
    summary.maxSlip = std::max(summary.maxSlip, openings.slip[e]);
  }
  if (summary.elements == 0) {
    return {};
  }
  if (summary.area > 0.0) {
    summary.meanOpening /= summary.area;
    summary.meanSlip /= summary.area;
  }
  return summary;
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
