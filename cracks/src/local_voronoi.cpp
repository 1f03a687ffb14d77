// Local Voronoi method (dissertation 2.2, Figs. 2.9 and 2.11): Voronoi cells
// only around the ends of broken bonds, validated by the empty-sphere test;
// each broken bond is drawn as its face, with the bond's attributes, or, when
// its faces fail validation or do not exist, reported as inconsistent.
#include <algorithm>
#include <cmath>
#include <cstring>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "methods.hpp"
#include <crackvis/cracks/local_voronoi.hpp>
#include <crackvis/cracks/particle_grid.hpp>

namespace crackvis::cracks {

Box defaultDomain(std::span<const Vec3> positions, std::span<const double> radius, int dimension) {
  // The centres' bounding box, not enlarged by the radius: a surface
  // particle's local cell then stops where its missing neighbours would have
  // cut it, so it is its true Voronoi cell and validation stays quiet on the
  // specimen's faces.
  Box box = dem::boundingBox(positions);
  const double largest = radius.empty() ? 0.0 : *std::max_element(radius.begin(), radius.end());
  if (dimension == 2) {
    box.lo.z = -largest;
    box.hi.z = largest;
  }
  return box;
}

namespace {

// The offset of the plane between i and j along n = x_j - x_i: the bisector
// for equal radii, the radical (power) plane |x - x_i|^2 - r_i^2 =
// |x - x_j|^2 - r_j^2 for unequal ones (radius empty: bisector).
double planeOffset(std::span<const Vec3> positions, std::span<const double> radius,
                   dem::ParticleIndex i, dem::ParticleIndex j, Vec3 n) {
  const Vec3 xi = positions[static_cast<std::size_t>(i)];
  const Vec3 xj = positions[static_cast<std::size_t>(j)];
  double offset = 0.5 * dem::dot(n, xi + xj);
  if (!radius.empty()) {
    const double ri = radius[static_cast<std::size_t>(i)];
    const double rj = radius[static_cast<std::size_t>(j)];
    offset += 0.5 * (ri * ri - rj * rj);
  }
  return offset;
}

bool clipByNeighbours(const BondGraph& graph, std::span<const Vec3> positions,
                      std::span<const double> radius, dem::ParticleIndex i, ConvexCell& cell) {
  const Vec3 xi = positions[static_cast<std::size_t>(i)];
  for (dem::BondIndex b : graph.bondsOf(i)) {
    const dem::ParticleIndex j = graph.otherEnd(b, i);
    const Vec3 n = positions[static_cast<std::size_t>(j)] - xi;
    // Keep the half-space closer to i (in power distance).
    if (!cell.clip(n, planeOffset(positions, radius, i, j, n), b, 1e-12 * dem::dot(n, n))) {
      return false;
    }
  }
  return true;
}

}  // namespace

void computeLocalVoronoiCell(const BondGraph& graph, std::span<const Vec3> positions,
                             dem::ParticleIndex i, const Box& box, ConvexCell& cell,
                             std::span<const double> radius) {
  cell.reset(box.lo, box.hi);
  clipByNeighbours(graph, positions, radius, i, cell);
}

namespace {

// Keeps the part of a convex polygon with dot(normal, p) <= offset; vertices
// within `tolerance` of the line count as on it. False when nothing is left.
bool clipPolygon(std::vector<Vec3>& polygon, std::vector<Vec3>& scratch, Vec3 normal, double offset,
                 double tolerance) {
  bool anyOut = false;
  bool anyIn = false;
  for (const Vec3& p : polygon) {
    const double d = dem::dot(normal, p) - offset;
    anyOut = anyOut || d > tolerance;
    anyIn = anyIn || d < -tolerance;
  }
  if (!anyOut) {
    return true;
  }
  if (!anyIn) {
    polygon.clear();
    return false;
  }
  scratch.clear();
  const std::size_t n = polygon.size();
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3 a = polygon[k];
    const Vec3 b = polygon[(k + 1) % n];
    const double da = dem::dot(normal, a) - offset;
    const double db = dem::dot(normal, b) - offset;
    if (da <= tolerance) {
      scratch.push_back(a);
    }
    if ((da < -tolerance && db > tolerance) || (da > tolerance && db < -tolerance)) {
      scratch.push_back(a + (da / (da - db)) * (b - a));
    }
  }
  std::swap(polygon, scratch);
  return polygon.size() >= 3;
}

}  // namespace

void computeLocalVoronoiFace(const BondGraph& graph, std::span<const Vec3> positions,
                             dem::ParticleIndex i, dem::BondIndex b, const Box& box,
                             std::vector<Vec3>& polygon, std::vector<Vec3>& scratch,
                             std::span<const double> radius) {
  const Vec3 xi = positions[static_cast<std::size_t>(i)];
  const dem::ParticleIndex j = graph.otherEnd(b, i);
  const Vec3 xj = positions[static_cast<std::size_t>(j)];
  const Vec3 n = xj - xi;
  const double length = dem::norm(n);
  polygon.clear();
  if (length == 0.0) {
    return;
  }
  // A square in the bisector plane, larger than the domain, counter-clockwise
  // about n; the other bisectors and the box's walls cut it down to the face.
  const Vec3 unit = (1.0 / length) * n;
  const Vec3 helper = std::abs(unit.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  Vec3 u = cross(unit, helper);
  u = (1.0 / dem::norm(u)) * u;
  const Vec3 w = cross(unit, u);
  const double half = 2.0 * dem::norm(box.hi - box.lo) + length;
  // The point of the (power) plane on the line x_i x_j.
  const bool bisector =
      radius.empty() || radius[static_cast<std::size_t>(i)] == radius[static_cast<std::size_t>(j)];
  const Vec3 mid = bisector ? 0.5 * (xi + xj)
                            : xi + (planeOffset(positions, radius, i, j, n) - dem::dot(n, xi)) /
                                       (length * length) * n;
  polygon = {mid + half * (-1.0 * u - w), mid + half * (u - w), mid + half * (u + w),
             mid + half * (w - u)};
  for (dem::BondIndex other : graph.bondsOf(i)) {
    if (other == b) {
      continue;
    }
    const dem::ParticleIndex k = graph.otherEnd(other, i);
    const Vec3 nk = positions[static_cast<std::size_t>(k)] - xi;
    if (!clipPolygon(polygon, scratch, nk, planeOffset(positions, radius, i, k, nk),
                     1e-12 * dem::dot(nk, nk))) {
      return;
    }
  }
  const double tolerance = 1e-12 * dem::norm(box.hi - box.lo);
  const Vec3 walls[6] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
  const double offsets[6] = {-box.lo.x, box.hi.x, -box.lo.y, box.hi.y, -box.lo.z, box.hi.z};
  for (int k = 0; k < 6; ++k) {
    if (!clipPolygon(polygon, scratch, walls[k], offsets[k], tolerance)) {
      return;
    }
  }
}

namespace {

// A face vertex carried by particles: their mean position plus an offset.
struct Carrier {
  static constexpr int kMax = 8;
  std::array<dem::ParticleIndex, kMax> particles{};
  int count = 0;
  Vec3 offset;

  Vec3 at(std::span<const Vec3> x) const {
    Vec3 mean{};
    for (int k = 0; k < count; ++k) {
      mean = mean + x[static_cast<std::size_t>(particles[static_cast<std::size_t>(k)])];
    }
    return offset + (1.0 / count) * mean;
  }
};

// A particle near a vertex under the sphere test, with r_k^2 - r_i^2.
struct Candidate {
  Vec3 position;
  double powerShift;
};

// Per-thread buffers, reused from particle to particle.
struct Scratch {
  ConvexCell cell;
  std::vector<char> valid;
  std::vector<Candidate> candidates;
  std::vector<Vec3> polygon;
  std::vector<Vec3> clipBuffer;
  std::vector<Vec3> faceVertices;
  std::vector<std::pair<dem::BondIndex, std::size_t>> faces;  // bond, first vertex
};

// One face of an end particle's cell that the output may need.
struct FaceRecord {
  dem::ParticleIndex particle;
  dem::BondIndex bond;
  bool valid;
  std::int32_t firstPoint;  // into the block's points
  std::int32_t pointCount;
};

struct CellBlock {
  std::vector<FaceRecord> faces;            // by particle (ascending), then bond
  std::vector<std::int32_t> particleStart;  // first face of each particle of the block
  std::vector<Vec3> points;
};

class LocalVoronoiExtractor final : public CrackExtractor {
 public:
  LocalVoronoiExtractor(const BondGraph& graph, int dimension, const ExtractOptions& options)
      : m_graph(graph), m_dimension(dimension), m_options(options) {}

  Method method() const override { return Method::kLocalVoronoi; }
  std::size_t inconsistentBondCount() const override { return m_inconsistent; }
  std::size_t memoryBytes() const override {
    return m_grid.memoryBytes() + m_rankOf.capacity() * sizeof(std::int32_t) +
           m_broken.capacity() * sizeof(dem::BondIndex) +
           m_faceOfBond.capacity() * sizeof(std::int32_t) + m_seenState.capacity() +
           m_materialBroken.capacity() * sizeof(dem::BondIndex) +
           m_faces.capacity() * sizeof(MaterialFace) + m_carriers.capacity() * sizeof(Carrier);
  }

  Status extract(const StepInput& step, CrackMesh& out) override {
    CRACKVIS_RETURN_IF_ERROR(checkStepInput(m_graph, step));
    out.clear();
    out.dimension = m_dimension;
    if (!step.referencePositions.empty() && !m_options.includeIntactFaces) {
      if (step.referencePositions.size() != step.positions.size()) {
        return invalidArgument(fmt::format("{} reference positions for N = {} particles",
                                           step.referencePositions.size(), step.positions.size()));
      }
      extractMaterial(step, out);
      return Status::ok();
    }
    const Box box =
        m_options.domain ? *m_options.domain : grownDefaultDomain(step.positions, step.radius);
    std::vector<dem::ParticleIndex> ends = endParticles(step.bondState);
    if (m_options.validate) {
      m_largestRadius = 0.0;
      for (double r : step.radius) {
        m_largestRadius = std::max(m_largestRadius, r);
      }
      m_grid.build(step.positions, 2.0 * m_largestRadius);
    }
    // Cells of the end particles, on all cores, in blocks of particles.
    const std::size_t blockCount = (ends.size() + kBlockSize - 1) / kBlockSize;
    std::vector<CellBlock> blocks(blockCount);
    tbb::parallel_for(std::size_t{0}, blockCount, [&](std::size_t k) {
      Scratch scratch;
      for (std::size_t e = k * kBlockSize; e < std::min(ends.size(), (k + 1) * kBlockSize); ++e) {
        blocks[k].particleStart.push_back(static_cast<std::int32_t>(blocks[k].faces.size()));
        if (m_options.includeIntactFaces) {
          collectCellFaces(step, box, ends[e], scratch, blocks[k]);
        } else {
          collectBrokenFaces(step, box, ends[e], scratch, blocks[k]);
        }
      }
      blocks[k].particleStart.push_back(static_cast<std::int32_t>(blocks[k].faces.size()));
    });
    assemble(step, blocks, out);
    return Status::ok();
  }

 private:
  Box grownDefaultDomain(std::span<const Vec3> positions, std::span<const double> radius) const {
    // A piece of a larger set (partition.hpp) is given the whole set's box
    // and largest radius: its own would clip the cells at its cut.
    const bool whole = m_options.specimenCentres.has_value();
    const double largest = whole            ? m_options.specimenLargestRadius
                           : radius.empty() ? 0.0
                                            : *std::max_element(radius.begin(), radius.end());
    Box box = whole ? *m_options.specimenCentres : defaultDomain(positions, radius, m_dimension);
    if (whole && m_dimension == 2) {
      box.lo.z = -largest;
      box.hi.z = largest;
    }
    if (m_options.domainMargin > 0.0 && largest > 0.0) {
      const double margin = m_options.domainMargin * largest;
      box.lo = box.lo - Vec3{margin, margin, m_dimension == 3 ? margin : 0.0};
      box.hi = box.hi + Vec3{margin, margin, m_dimension == 3 ? margin : 0.0};
    }
    return box;
  }

  // Material surfaces: with a reference configuration, each face is made
  // once, in the reference geometry (where it is validated too), when its
  // bond is first seen broken, and then carried by its particles: every
  // vertex is stored as a combination of particle positions, so the face
  // follows the specimen however far the crack opens. A step costs the diff
  // of its bond states, the faces of the bonds that broke since the last
  // step, and the carried points: nothing is recomputed for older breaks.
  void extractMaterial(const StepInput& step, CrackMesh& out) {
    if (!m_referenceReady) {
      prepareReference(step);
    }
    makeFaces(step, newlyBroken(step.bondState));
    std::vector<dem::BondIndex> faceBonds;
    std::vector<dem::BondIndex> inconsistent;
    m_faceLines.clear();
    out.points.reserve(m_carriers.size());
    for (dem::BondIndex bond : m_materialBroken) {
      const MaterialFace& face =
          m_faces[static_cast<std::size_t>(m_faceOfBond[static_cast<std::size_t>(bond)])];
      if (face.valid) {
        addCarriedFace(face, step.positions, out);
        faceBonds.push_back(bond);
      } else {
        inconsistent.push_back(bond);
      }
    }
    finish(step, faceBonds, inconsistent, out);
  }

  void prepareReference(const StepInput& step) {
    const std::span<const Vec3> reference = step.referencePositions;
    m_referenceBox =
        m_options.domain ? *m_options.domain : grownDefaultDomain(reference, step.radius);
    m_largestRadius = 0.0;
    for (double r : step.radius) {
      m_largestRadius = std::max(m_largestRadius, r);
    }
    if (m_options.validate) {
      m_grid.build(reference, 2.0 * m_largestRadius);
    }
    m_faceOfBond.assign(m_graph.bondCount(), -1);
    m_seenState.assign(m_graph.bondCount(), 0);
    m_materialBroken.clear();
    m_referenceReady = true;
  }

  // The bonds broken now that were intact at the last step, in bond order;
  // keeps m_materialBroken, all broken bonds in bond order, up to date (also
  // when a bond heals, which DEM codes do not do but a file may).
  std::vector<dem::BondIndex> newlyBroken(std::span<const std::uint8_t> state) {
    std::vector<dem::BondIndex> fresh;
    bool healed = false;
    constexpr std::size_t kChunk = 64;
    for (std::size_t from = 0; from < state.size(); from += kChunk) {
      const std::size_t count = std::min(kChunk, state.size() - from);
      // Most chunks are unchanged from step to step: compare them whole.
      if (std::memcmp(state.data() + from, m_seenState.data() + from, count) == 0) {
        continue;
      }
      for (std::size_t b = from; b < from + count; ++b) {
        const bool broken = state[b] != 0;
        if (broken != (m_seenState[b] != 0)) {
          if (broken) {
            fresh.push_back(static_cast<dem::BondIndex>(b));
          } else {
            healed = true;
          }
        }
        m_seenState[b] = state[b];
      }
    }
    if (healed) {
      m_materialBroken.clear();
      for (std::size_t b = 0; b < state.size(); ++b) {
        if (state[b] != 0) {
          m_materialBroken.push_back(static_cast<dem::BondIndex>(b));
        }
      }
    } else if (!fresh.empty()) {
      const auto middle = static_cast<std::ptrdiff_t>(m_materialBroken.size());
      m_materialBroken.insert(m_materialBroken.end(), fresh.begin(), fresh.end());
      std::inplace_merge(m_materialBroken.begin(), m_materialBroken.begin() + middle,
                         m_materialBroken.end());
    }
    return fresh;
  }

  // The faces of bonds never seen broken before, on all cores in blocks,
  // then remembered in bond order (the same for any thread count).
  void makeFaces(const StepInput& step, const std::vector<dem::BondIndex>& fresh) {
    std::vector<dem::BondIndex> missing;
    for (dem::BondIndex bond : fresh) {
      if (faceIndexOf(bond) < 0) {
        missing.push_back(bond);
      }
    }
    std::vector<NewFace> made(missing.size());
    const std::size_t blockCount = (missing.size() + kBlockSize - 1) / kBlockSize;
    tbb::parallel_for(std::size_t{0}, blockCount, [&](std::size_t k) {
      Scratch scratch;
      for (std::size_t e = k * kBlockSize; e < std::min(missing.size(), (k + 1) * kBlockSize);
           ++e) {
        made[e] = makeFace(step, missing[e], scratch);
      }
    });
    for (NewFace& face : made) {
      m_faceOfBond[static_cast<std::size_t>(face.bond)] = static_cast<std::int32_t>(m_faces.size());
      m_faces.push_back({face.valid, static_cast<std::int32_t>(m_carriers.size()),
                         static_cast<std::int32_t>(face.carriers.size())});
      m_carriers.insert(m_carriers.end(), face.carriers.begin(), face.carriers.end());
    }
  }

  std::int32_t faceIndexOf(dem::BondIndex bond) const {
    return m_faceOfBond[static_cast<std::size_t>(bond)];
  }

  struct NewFace {
    dem::BondIndex bond = -1;
    bool valid = false;
    std::vector<Carrier> carriers;
  };
  struct MaterialFace {
    bool valid;
    std::int32_t first;  // into m_carriers
    std::int32_t count;
  };

  // A broken bond's face in the reference geometry, as each end's cell has
  // it: drawn (from the first end, its vertices turned into carriers) when
  // it exists at both ends, passes validation at both and has at least two
  // vertices; else the bond is inconsistent.
  NewFace makeFace(const StepInput& step, dem::BondIndex b, Scratch& s) const {
    const std::span<const Vec3> reference = step.referencePositions;
    const dem::Bond& pair = m_graph.bond(b);
    NewFace face{b, true, {}};
    for (dem::ParticleIndex i : {pair.first, pair.second}) {
      computeLocalVoronoiFace(m_graph, reference, i, b, m_referenceBox, s.polygon, s.clipBuffer,
                              step.radius);
      bool valid = s.polygon.size() >= 3;
      if (valid && m_options.validate) {
        s.valid.assign(s.polygon.size(), 2);
        validateVertices(reference, step.radius, i, s.polygon, s.valid, s.candidates);
        valid = std::all_of(s.valid.begin(), s.valid.end(), [](char v) { return v != 0; });
      }
      if (!valid) {
        face.valid = false;
        face.carriers.clear();
        return face;
      }
      if (i != pair.first) {
        continue;
      }
      const dem::ParticleIndex j = pair.second;
      for (std::size_t k = 0; k < s.polygon.size(); ++k) {
        // In 2D the prism's side face stands for an edge: its lower vertices.
        if (m_dimension == 2 && s.polygon[k].z >= 0.0) {
          continue;
        }
        face.carriers.push_back(carrierOf(reference, step.radius, i, j, s.polygon[k]));
      }
    }
    face.valid = face.carriers.size() >= 2;
    return face;
  }

  // A vertex of face (i, j) carried by the particles that define it: those
  // at the least power distance from it (within 1e-6 relative), among i, j
  // and their neighbours. It moves by the mean of their displacements since
  // the reference: a rigid translation moves it with them, an opening crack
  // by a fraction of the opening, so faces stay between the halves. The set
  // depends on the vertex alone, not on the face, so faces that share a
  // vertex keep sharing it (also where more than four particles define it,
  // as at an FCC lattice's octahedral holes).
  Carrier carrierOf(std::span<const Vec3> x, std::span<const double> radius, dem::ParticleIndex i,
                    dem::ParticleIndex j, Vec3 v) const {
    if (m_dimension == 2) {
      v.z = 0.0;
    }
    auto power = [&](dem::ParticleIndex k) {
      const Vec3 d = v - x[static_cast<std::size_t>(k)];
      const double r = radius.empty() ? 0.0 : radius[static_cast<std::size_t>(k)];
      return dem::dot(d, d) - r * r;
    };
    const double least = std::min(power(i), power(j));
    const double tolerance = 1e-6 * std::max(dem::dot(v - x[static_cast<std::size_t>(i)],
                                                      v - x[static_cast<std::size_t>(i)]),
                                             1e-300);
    Carrier carrier;
    auto consider = [&](dem::ParticleIndex k) {
      if (carrier.count < Carrier::kMax && power(k) <= least + tolerance &&
          std::find(carrier.particles.begin(), carrier.particles.begin() + carrier.count, k) ==
              carrier.particles.begin() + carrier.count) {
        carrier.particles[static_cast<std::size_t>(carrier.count++)] = k;
      }
    };
    consider(i);
    consider(j);
    for (dem::ParticleIndex end : {i, j}) {
      for (dem::BondIndex b : m_graph.bondsOf(end)) {
        consider(m_graph.otherEnd(b, end));
      }
    }
    std::sort(carrier.particles.begin(), carrier.particles.begin() + carrier.count);
    Vec3 mean{};
    for (int k = 0; k < carrier.count; ++k) {
      mean = mean + x[static_cast<std::size_t>(carrier.particles[static_cast<std::size_t>(k)])];
    }
    carrier.offset = v - (1.0 / carrier.count) * mean;
    return carrier;
  }

  void addCarriedFace(const MaterialFace& face, std::span<const Vec3> positions, CrackMesh& out) {
    const auto first = static_cast<std::int32_t>(out.points.size());
    for (std::int32_t k = 0; k < face.count; ++k) {
      out.points.push_back(m_carriers[static_cast<std::size_t>(face.first + k)].at(positions));
    }
    PrimitiveList& target = m_dimension == 2 ? m_faceLines : out.polygons;
    for (std::int32_t k = 0; k < face.count; ++k) {
      target.connectivity.push_back(first + k);
    }
    target.offsets.push_back(static_cast<std::int32_t>(target.connectivity.size()));
  }

  // The broken bonds, and the particles at their ends with their rank.
  std::vector<dem::ParticleIndex> endParticles(std::span<const std::uint8_t> state) {
    m_rankOf.assign(m_graph.particleCount(), -1);
    m_broken.clear();
    for (std::size_t b = 0; b < state.size(); ++b) {
      if (state[b] != 0) {
        const dem::Bond& bond = m_graph.bond(static_cast<dem::BondIndex>(b));
        m_rankOf[static_cast<std::size_t>(bond.first)] = 0;
        m_rankOf[static_cast<std::size_t>(bond.second)] = 0;
        m_broken.push_back(static_cast<dem::BondIndex>(b));
      }
    }
    std::vector<dem::ParticleIndex> ends;
    for (std::size_t i = 0; i < m_rankOf.size(); ++i) {
      if (m_rankOf[i] == 0) {
        m_rankOf[i] = static_cast<std::int32_t>(ends.size());
        ends.push_back(static_cast<dem::ParticleIndex>(i));
      }
    }
    return ends;
  }

  bool wanted(const StepInput& step, dem::ParticleIndex i, dem::BondIndex b) const {
    if (step.bondState[static_cast<std::size_t>(b)] != 0) {
      return true;
    }
    if (!m_options.includeIntactFaces) {
      return false;
    }
    // An intact face is drawn once: from the lower end, or from the only end
    // that has a cell.
    const dem::ParticleIndex j = m_graph.otherEnd(b, i);
    return i < j || m_rankOf[static_cast<std::size_t>(j)] < 0;
  }

  // The empty-sphere test of the vertices marked 2 (to test) in `valid`,
  // which become 1 (valid) or 0. Every sphere
  // lies within twice the farthest vertex's distance of x_i, so one grid
  // query per cell finds all particles that could violate any of them.
  //
  // With unequal radii the test is on power distances: a vertex of i's cell
  // fails when some particle k has |v - x_k|^2 - (r_k^2 - r_i^2) <
  // (keep |v - x_i|)^2; for equal radii that is the plain empty-sphere test.
  void validateVertices(std::span<const Vec3> positions, std::span<const double> radius,
                        dem::ParticleIndex i, const std::vector<Vec3>& vertices,
                        std::vector<char>& valid, std::vector<Candidate>& candidates) const {
    const Vec3 xi = positions[static_cast<std::size_t>(i)];
    const double ri2 = radius[static_cast<std::size_t>(i)] * radius[static_cast<std::size_t>(i)];
    auto project = [&](Vec3 v) {
      if (m_dimension == 2) {
        v.z = 0.0;  // the prism's vertices stand for the 2D vertex below them
      }
      return v;
    };
    double farthest = 0.0;
    for (std::size_t v = 0; v < vertices.size(); ++v) {
      if (valid[v] == 2) {
        farthest = std::max(farthest, dem::norm(project(vertices[v]) - xi));
      }
    }
    if (farthest == 0.0) {
      return;
    }
    const double reach = 2.0 * farthest + m_largestRadius;
    candidates.clear();
    m_grid.forEachNear(xi, reach, [&](std::int32_t k) {
      const Vec3 xk = positions[static_cast<std::size_t>(k)];
      if (k != i && dem::dot(xk - xi, xk - xi) <= reach * reach) {
        const double rk = radius[static_cast<std::size_t>(k)];
        candidates.push_back({xk, rk * rk - ri2});
      }
    });
    const double keep = 1.0 - m_options.validationTolerance;
    for (std::size_t v = 0; v < vertices.size(); ++v) {
      if (valid[v] != 2) {
        continue;
      }
      valid[v] = 1;
      const Vec3 vertex = project(vertices[v]);
      const Vec3 toCentre = vertex - xi;
      const double inner2 = dem::dot(toCentre, toCentre) * keep * keep;
      for (const Candidate& k : candidates) {
        const Vec3 d = k.position - vertex;
        if (dem::dot(d, d) - k.powerShift < inner2) {
          valid[v] = 0;
          break;
        }
      }
    }
  }

  // Appends a face's vertices to the block (in 2D the prism's side face
  // stands for an edge: its two lower vertices).
  void appendFace(dem::ParticleIndex i, dem::BondIndex bond, bool valid, const Vec3* vertices,
                  std::size_t count, CellBlock& block) const {
    FaceRecord record{i, bond, valid, static_cast<std::int32_t>(block.points.size()), 0};
    for (std::size_t k = 0; k < count; ++k) {
      const Vec3 p = vertices[k];
      if (m_dimension == 2) {
        if (p.z < 0.0) {
          block.points.push_back({p.x, p.y, 0.0});
        }
      } else {
        block.points.push_back(p);
      }
    }
    record.pointCount = static_cast<std::int32_t>(block.points.size()) - record.firstPoint;
    block.faces.push_back(record);
  }

  // Only the faces of i's broken bonds: each is its bisector plane clipped by
  // i's other bisectors, so the rest of the cell is never built.
  void collectBrokenFaces(const StepInput& step, const Box& box, dem::ParticleIndex i, Scratch& s,
                          CellBlock& block) const {
    s.faceVertices.clear();
    s.faces.clear();
    for (dem::BondIndex b : m_graph.bondsOf(i)) {
      if (step.bondState[static_cast<std::size_t>(b)] == 0) {
        continue;
      }
      computeLocalVoronoiFace(m_graph, step.positions, i, b, box, s.polygon, s.clipBuffer,
                              step.radius);
      if (s.polygon.size() >= 3) {
        s.faces.push_back({b, s.faceVertices.size()});
        s.faceVertices.insert(s.faceVertices.end(), s.polygon.begin(), s.polygon.end());
      }
    }
    s.faces.push_back({-1, s.faceVertices.size()});  // sentinel: end of the last face
    s.valid.assign(s.faceVertices.size(), m_options.validate ? 2 : 1);
    if (m_options.validate) {
      validateVertices(step.positions, step.radius, i, s.faceVertices, s.valid, s.candidates);
    }
    for (std::size_t f = 0; f + 1 < s.faces.size(); ++f) {
      const std::size_t first = s.faces[f].second;
      const std::size_t last = s.faces[f + 1].second;
      bool valid = true;
      for (std::size_t v = first; v < last; ++v) {
        valid = valid && s.valid[v] != 0;
      }
      appendFace(i, s.faces[f].first, valid, s.faceVertices.data() + first, last - first, block);
    }
  }

  // The whole cell, when the faces of intact bonds are wanted too.
  void collectCellFaces(const StepInput& step, const Box& box, dem::ParticleIndex i, Scratch& s,
                        CellBlock& block) const {
    computeLocalVoronoiCell(m_graph, step.positions, i, box, s.cell, step.radius);
    const auto& vertices = s.cell.vertices();
    std::vector<std::pair<dem::BondIndex, std::size_t>> faces;
    for (std::size_t f = 0; f < s.cell.faceCount(); ++f) {
      if (s.cell.faceLabel(f) >= 0 && wanted(step, i, s.cell.faceLabel(f))) {
        faces.push_back({s.cell.faceLabel(f), f});
      }
    }
    // Only vertices of faces that may be drawn need the sphere test.
    s.valid.assign(vertices.size(), 1);
    if (m_options.validate) {
      for (const auto& face : faces) {
        for (std::int32_t v : s.cell.face(face.second)) {
          s.valid[static_cast<std::size_t>(v)] = 2;  // to test
        }
      }
      validateVertices(step.positions, step.radius, i, vertices, s.valid, s.candidates);
    }
    std::sort(faces.begin(), faces.end());
    for (const auto& [bond, f] : faces) {
      s.faceVertices.clear();
      bool valid = true;
      for (std::int32_t v : s.cell.face(f)) {
        valid = valid && s.valid[static_cast<std::size_t>(v)] != 0;
        s.faceVertices.push_back(vertices[static_cast<std::size_t>(v)]);
      }
      appendFace(i, bond, valid, s.faceVertices.data(), s.faceVertices.size(), block);
    }
  }

  // The face of particle i's cell made by bond b, if i has a cell and the face exists.
  const FaceRecord* find(const std::vector<CellBlock>& blocks, dem::ParticleIndex i,
                         dem::BondIndex b, const CellBlock** owner) const {
    const std::int32_t rank = m_rankOf[static_cast<std::size_t>(i)];
    if (rank < 0) {
      return nullptr;
    }
    const CellBlock& block = blocks[static_cast<std::size_t>(rank) / kBlockSize];
    const std::size_t local = static_cast<std::size_t>(rank) % kBlockSize;
    for (std::int32_t f = block.particleStart[local]; f < block.particleStart[local + 1]; ++f) {
      if (block.faces[static_cast<std::size_t>(f)].bond == b) {
        *owner = &block;
        return &block.faces[static_cast<std::size_t>(f)];
      }
    }
    return nullptr;
  }

  void addFace(const FaceRecord& record, const CellBlock& block, CrackMesh& out) {
    const auto first = static_cast<std::int32_t>(out.points.size());
    out.points.insert(out.points.end(), block.points.begin() + record.firstPoint,
                      block.points.begin() + record.firstPoint + record.pointCount);
    PrimitiveList& target = m_dimension == 2 ? m_faceLines : out.polygons;
    for (std::int32_t k = 0; k < record.pointCount; ++k) {
      target.connectivity.push_back(first + k);
    }
    target.offsets.push_back(static_cast<std::int32_t>(target.connectivity.size()));
  }

  // Broken bonds in bond order: a face if consistent, else an inconsistency
  // line; then, on request, the faces of intact bonds.
  void assemble(const StepInput& step, const std::vector<CellBlock>& blocks, CrackMesh& out) {
    std::vector<dem::BondIndex> faceBonds;
    std::vector<dem::BondIndex> inconsistent;
    m_faceLines.clear();
    for (dem::BondIndex bond : m_broken) {
      const dem::Bond& pair = m_graph.bond(bond);
      const CellBlock* firstBlock = nullptr;
      const CellBlock* secondBlock = nullptr;
      const FaceRecord* first = find(blocks, pair.first, bond, &firstBlock);
      const FaceRecord* second = find(blocks, pair.second, bond, &secondBlock);
      const bool consistent = first != nullptr && second != nullptr && first->valid &&
                              second->valid && first->pointCount >= 2;
      if (consistent) {
        addFace(*first, *firstBlock, out);
        faceBonds.push_back(bond);
      } else {
        inconsistent.push_back(bond);
      }
    }
    if (m_options.includeIntactFaces) {
      for (const CellBlock& block : blocks) {
        for (const FaceRecord& record : block.faces) {
          if (step.bondState[static_cast<std::size_t>(record.bond)] == 0) {
            addFace(record, block, out);
            faceBonds.push_back(record.bond);
          }
        }
      }
    }
    finish(step, faceBonds, inconsistent, out);
  }

  // Inconsistency lines, the 2D face segments and the attributes, after the
  // faces of the step are known.
  void finish(const StepInput& step, const std::vector<dem::BondIndex>& faceBonds,
              const std::vector<dem::BondIndex>& inconsistent, CrackMesh& out) {
    m_inconsistent = inconsistent.size();
    // Inconsistent bonds: a line between the particle centres (VTK order:
    // lines come before polygons, and in 2D before the face segments).
    for (dem::BondIndex bond : inconsistent) {
      const dem::Bond& pair = m_graph.bond(bond);
      const auto first = static_cast<std::int32_t>(out.points.size());
      out.points.push_back(step.positions[static_cast<std::size_t>(pair.first)]);
      out.points.push_back(step.positions[static_cast<std::size_t>(pair.second)]);
      out.lines.add({first, first + 1});
    }
    for (std::size_t k = 0; k < m_faceLines.size(); ++k) {
      out.lines.addRange(m_faceLines.connectivity.begin() + m_faceLines.offsets[k],
                         m_faceLines.connectivity.begin() + m_faceLines.offsets[k + 1]);
    }
    std::vector<dem::BondIndex> primitiveBonds = inconsistent;
    primitiveBonds.insert(primitiveBonds.end(), faceBonds.begin(), faceBonds.end());
    appendBondAttributes(step, primitiveBonds, out.cellData);
    AttributeArray flag{"inconsistent", AttributeType::kInt32, 1, {}};
    flag.values.assign(inconsistent.size(), 1.0);
    flag.values.resize(primitiveBonds.size(), 0.0);
    out.cellData.push_back(std::move(flag));
  }

  const BondGraph& m_graph;
  int m_dimension;
  ExtractOptions m_options;
  ParticleGrid m_grid;
  double m_largestRadius = 0.0;
  // Material faces, by (particle, bond); made in the reference geometry.
  bool m_referenceReady = false;
  Box m_referenceBox;
  std::vector<std::int32_t> m_faceOfBond;  // [M] into m_faces, -1 while never broken
  std::vector<std::uint8_t> m_seenState;   // [M] the bond states of the last step
  std::vector<dem::BondIndex> m_materialBroken;
  std::vector<MaterialFace> m_faces;
  std::vector<Carrier> m_carriers;
  std::vector<std::int32_t> m_rankOf;  // [N] rank among end particles, -1 if none
  std::vector<dem::BondIndex> m_broken;
  PrimitiveList m_faceLines;
  std::size_t m_inconsistent = 0;
};

}  // namespace

std::unique_ptr<CrackExtractor> makeLocalVoronoi(const BondGraph& graph, int dimension,
                                                 const ExtractOptions& options) {
  return std::make_unique<LocalVoronoiExtractor>(graph, dimension, options);
}

}  // namespace crackvis::cracks
