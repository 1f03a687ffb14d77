// Cell centre method (dissertation 2.3): for each broken bond, the polygon
// through the centroids (eq. 2.3) of the cells around it, in order around the
// bond. One point per cell, shared by every bond of that cell, so the faces
// form a connected mesh. With merged octahedra, the two pyramids of an
// octahedron count as one cell centred at the octahedron's centroid; on an
// undeformed FCC lattice the faces are then exactly the Voronoi faces.
//
// Bonds on the lattice's boundary have an open fan of cells; their polygon is
// closed through the bond's midpoint.
#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

#include "methods.hpp"

namespace crackvis::cracks {
namespace {

using dem::BondIndex;
using dem::ParticleIndex;

// A cell around a bond and the two faces it shares with its neighbours around
// the bond, identified by the face's nodes other than the bond's ends.
struct FanEntry {
  CellIndex cell;
  std::array<std::int64_t, 2> faces;
};

std::int64_t triangleKey(ParticleIndex third) {
  return third;
}
std::int64_t quadKey(ParticleIndex a, ParticleIndex b) {
  return -1 - ((static_cast<std::int64_t>(std::min(a, b)) << 31) | std::max(a, b));
}

class CellCentreExtractor final : public CrackExtractor {
 public:
  CellCentreExtractor(const BondGraph& graph, int dimension, const ExtractOptions& options,
                      const ExplicitCells* cells)
      : m_decomposition(graph, dimension, cells),
        m_merge(options.mergeOctahedra && dimension == 3),
        m_pointOfCell() {}

  Method method() const override { return Method::kCellCentre; }
  const LatticeDecomposition* decomposition() const override { return &m_decomposition; }
  std::size_t memoryBytes() const override {
    return m_decomposition.memoryBytes() + m_pointOfCell.capacity() * sizeof(std::int32_t) +
           m_centreCells.capacity() * sizeof(CellIndex) + m_fans.capacity() * sizeof(Fan) +
           m_fanCells.capacity() * sizeof(CellIndex);
  }

  Status extract(const StepInput& step, CrackMesh& out) override {
    CRACKVIS_RETURN_IF_ERROR(checkStepInput(m_decomposition.graph(), step));
    m_decomposition.update(step.bondState);
    out.clear();
    out.dimension = m_decomposition.dimension();
    computeCentres(step.positions, out.points);
    std::vector<BondIndex> broken;
    for (std::size_t b = 0; b < step.bondState.size(); ++b) {
      if (step.bondState[b] != 0) {
        broken.push_back(static_cast<BondIndex>(b));
      }
    }
    // Bonds with an open fan need their midpoint as a point: reserve one per
    // broken bond after the centres, in bond order.
    const auto midpointBase = static_cast<std::int32_t>(out.points.size());
    out.points.resize(out.points.size() + broken.size());
    tbb::parallel_for(std::size_t{0}, broken.size(), [&](std::size_t k) {
      const dem::Bond& bond = m_decomposition.graph().bond(broken[k]);
      out.points[static_cast<std::size_t>(midpointBase) + k] =
          0.5 * (step.positions[static_cast<std::size_t>(bond.first)] +
                 step.positions[static_cast<std::size_t>(bond.second)]);
    });
    updateFans(broken);
    std::vector<std::int32_t> tags;
    fillInBlocks(broken.size(), m_blocks, out, tags,
                 [&](std::size_t first, std::size_t last, PrimitiveBlock& block) {
                   std::vector<std::int32_t> polygon;
                   for (std::size_t k = first; k < last; ++k) {
                     emitBond(broken[k], m_fans[k], midpointBase + static_cast<std::int32_t>(k),
                              step.positions, out.points, polygon, block);
                   }
                 });
    std::vector<BondIndex> primitiveBonds(tags.begin(), tags.end());
    appendBondAttributes(step, primitiveBonds, out.cellData);
    dropUnusedMidpoints(out, midpointBase);
    return Status::ok();
  }

 private:
  CellIndex representative(CellIndex c) const {
    const LatticeCell& cell = m_decomposition.cell(c);
    return m_merge && cell.partnerOffset < 0 ? c + cell.partnerOffset : c;
  }

  // One point per (merged) cell that holds a broken bond, in cell order.
  void computeCentres(std::span<const Vec3> positions, std::vector<Vec3>& points) {
    const auto& cells = m_decomposition.cells();
    m_pointOfCell.assign(cells.size(), -1);
    m_centreCells.clear();
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const bool broken =
          cells[c].brokenMask != 0 ||
          (m_merge && cells[c].partnerOffset != 0 &&
           cells[c + static_cast<std::size_t>(cells[c].partnerOffset)].brokenMask != 0);
      const auto rep = static_cast<std::size_t>(representative(static_cast<CellIndex>(c)));
      if (broken && m_pointOfCell[rep] < 0) {
        m_pointOfCell[rep] = static_cast<std::int32_t>(m_centreCells.size());
        m_centreCells.push_back(static_cast<CellIndex>(rep));
      }
    }
    points.resize(m_centreCells.size());
    tbb::parallel_for(std::size_t{0}, m_centreCells.size(),
                      [&](std::size_t k) { points[k] = centroid(m_centreCells[k], positions); });
  }

  Vec3 centroid(CellIndex c, std::span<const Vec3> positions) const {
    const LatticeCell& cell = m_decomposition.cell(c);
    Vec3 sum{};
    int count = cell.nodeCount();
    for (int k = 0; k < count; ++k) {
      sum = sum + positions[static_cast<std::size_t>(cell.nodes[static_cast<std::size_t>(k)])];
    }
    if (m_merge && cell.partnerOffset > 0) {  // the octahedron: add the other apex
      sum = sum + positions[static_cast<std::size_t>(m_decomposition.cell(c + 1).nodes[4])];
      ++count;
    }
    return (1.0 / count) * sum;
  }

  // The faces of a (merged) cell that contain the bond (a, b).
  std::array<std::int64_t, 2> facesAround(CellIndex c, ParticleIndex a, ParticleIndex b) const {
    const LatticeCell& cell = m_decomposition.cell(c);
    std::array<std::int64_t, 2> keys{0, 0};
    int found = 0;
    if (cell.type == CellType::kTetrahedron) {
      for (int k = 0; k < 4; ++k) {
        const ParticleIndex p = cell.nodes[static_cast<std::size_t>(k)];
        if (p != a && p != b && found < 2) {
          keys[static_cast<std::size_t>(found++)] = triangleKey(p);
        }
      }
      return keys;
    }
    if (m_merge) {
      // Octahedron: the faces through (a, b) are (a, b, k) for the two other
      // particles that are neither a, b nor opposite to them.
      const LatticeCell& partner = m_decomposition.cell(c + 1);
      const std::array<ParticleIndex, 6> nodes{cell.nodes[0], cell.nodes[1], cell.nodes[2],
                                               cell.nodes[3], cell.nodes[4], partner.nodes[4]};
      const std::array<int, 6> opposite{2, 3, 0, 1, 5, 4};
      const int ia = static_cast<int>(std::find(nodes.begin(), nodes.end(), a) - nodes.begin());
      const int ib = static_cast<int>(std::find(nodes.begin(), nodes.end(), b) - nodes.begin());
      for (int k = 0; k < 6; ++k) {
        if (k != ia && k != ib && k != opposite[static_cast<std::size_t>(ia)] &&
            k != opposite[static_cast<std::size_t>(ib)] && found < 2) {
          keys[static_cast<std::size_t>(found++)] = triangleKey(nodes[static_cast<std::size_t>(k)]);
        }
      }
      return keys;
    }
    // Pyramid: a base edge lies in the base and one side; a side edge in two sides.
    const int la = cell.localNode(a);
    const int lb = cell.localNode(b);
    if (la < 4 && lb < 4) {
      const int third =
          (std::max(la, lb) == 3 && std::min(la, lb) == 0) ? 1 : (std::max(la, lb) + 1) % 4;
      const int fourth = (third + 1) % 4;
      keys[0] = quadKey(cell.nodes[static_cast<std::size_t>(third)],
                        cell.nodes[static_cast<std::size_t>(fourth)]);
      keys[1] = triangleKey(cell.nodes[4]);
      return keys;
    }
    const int base = la < 4 ? la : lb;
    keys[0] = triangleKey(cell.nodes[static_cast<std::size_t>((base + 1) % 4)]);
    keys[1] = triangleKey(cell.nodes[static_cast<std::size_t>((base + 3) % 4)]);
    return keys;
  }

  // Orders the fan by walking from cell to cell through shared faces; returns
  // false when the fan is not a simple path or cycle (then angles decide).
  static bool walkFan(std::vector<FanEntry>& fan, bool& open) {
    const std::size_t n = fan.size();
    auto sharedWith = [&](std::size_t k, std::int64_t face) -> std::ptrdiff_t {
      for (std::size_t other = 0; other < n; ++other) {
        if (other != k && (fan[other].faces[0] == face || fan[other].faces[1] == face)) {
          return static_cast<std::ptrdiff_t>(other);
        }
      }
      return -1;
    };
    // Start at an open end if there is one (lowest cell first: fan is sorted).
    std::size_t start = 0;
    int startFace = 0;
    open = false;
    for (std::size_t k = 0; k < n && !open; ++k) {
      for (int f = 0; f < 2; ++f) {
        if (sharedWith(k, fan[k].faces[static_cast<std::size_t>(f)]) < 0) {
          start = k;
          startFace = f;  // the free face; walk out through the other one
          open = true;
          break;
        }
      }
    }
    std::vector<FanEntry> ordered{fan[start]};
    std::vector<char> used(n, 0);
    used[start] = 1;
    std::int64_t through = fan[start].faces[static_cast<std::size_t>(1 - startFace)];
    std::size_t current = start;
    while (ordered.size() < n) {
      const std::ptrdiff_t next = sharedWith(current, through);
      if (next < 0 || used[static_cast<std::size_t>(next)]) {
        return false;
      }
      const auto& entry = fan[static_cast<std::size_t>(next)];
      through = entry.faces[0] == through ? entry.faces[1] : entry.faces[0];
      used[static_cast<std::size_t>(next)] = 1;
      ordered.push_back(entry);
      current = static_cast<std::size_t>(next);
    }
    fan = std::move(ordered);
    return true;
  }

  void sortByAngle(std::vector<std::int32_t>& polygon, const std::vector<Vec3>& points, Vec3 origin,
                   Vec3 axis) const {
    const Vec3 helper = std::abs(axis.x) < 0.9 * dem::norm(axis) ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    const Vec3 u = cross(axis, helper);
    const Vec3 w = cross(axis, u);
    std::sort(polygon.begin(), polygon.end(), [&](std::int32_t p, std::int32_t q) {
      const Vec3 dp = points[static_cast<std::size_t>(p)] - origin;
      const Vec3 dq = points[static_cast<std::size_t>(q)] - origin;
      return std::atan2(dem::dot(dp, w), dem::dot(dp, u)) <
             std::atan2(dem::dot(dq, w), dem::dot(dq, u));
    });
  }

  // The cells around a broken bond, in order around it. They are all made
  // when the bond's end particles are processed, which happens the step it
  // breaks, so the fan is computed once and only the centroids move later.
  struct Fan {
    BondIndex bond;
    std::int32_t first;  // into m_fanCells
    std::uint8_t count;
    bool open;    // the bond is on the lattice's boundary: close through its midpoint
    bool walked;  // ordered by shared faces; else angles decide, every step
  };

  void buildFan(BondIndex b, std::vector<CellIndex>& cells, std::vector<FanEntry>& fan, bool& open,
                bool& walked) const {
    const dem::Bond& bond = m_decomposition.graph().bond(b);
    m_decomposition.cellsOfBond(b, cells);
    fan.clear();
    for (CellIndex c : cells) {
      const CellIndex rep = representative(c);
      if (std::none_of(fan.begin(), fan.end(), [&](const FanEntry& e) { return e.cell == rep; })) {
        fan.push_back({rep, m_decomposition.dimension() == 3
                                ? facesAround(rep, bond.first, bond.second)
                                : std::array<std::int64_t, 2>{0, 0}});
      }
    }
    std::sort(fan.begin(), fan.end(),
              [](const FanEntry& x, const FanEntry& y) { return x.cell < y.cell; });
    open = false;
    walked = true;
    if (m_decomposition.dimension() == 3 && fan.size() > 1) {
      walked = walkFan(fan, open);
    }
  }

  // Keeps m_fans sorted by bond and equal to the broken bonds: new fans for
  // bonds broken since the last step (computed on all cores), or all anew
  // when a bond healed (the viewer stepped back).
  void updateFans(const std::vector<BondIndex>& broken) {
    std::vector<BondIndex> fresh;
    std::size_t kept = 0;
    bool healed = false;
    for (const Fan& fan : m_fans) {
      healed = healed || !std::binary_search(broken.begin(), broken.end(), fan.bond);
    }
    if (healed) {
      m_fans.clear();
      m_fanCells.clear();
    }
    for (BondIndex b : broken) {
      while (kept < m_fans.size() && m_fans[kept].bond < b) {
        ++kept;
      }
      if (kept == m_fans.size() || m_fans[kept].bond != b) {
        fresh.push_back(b);
      }
    }
    if (fresh.empty()) {
      return;
    }
    std::vector<std::vector<CellIndex>> cells(fresh.size());
    std::vector<Fan> made(fresh.size());
    tbb::parallel_for(std::size_t{0}, fresh.size(), [&](std::size_t k) {
      std::vector<CellIndex> scratch;
      std::vector<FanEntry> fan;
      bool open = false;
      bool walked = true;
      buildFan(fresh[k], scratch, fan, open, walked);
      for (const FanEntry& entry : fan) {
        cells[k].push_back(entry.cell);
      }
      made[k] = {fresh[k], 0, static_cast<std::uint8_t>(fan.size()), open, walked};
    });
    // Merge old and new fans by bond.
    std::vector<Fan> fans;
    std::vector<CellIndex> fanCells;
    fans.reserve(m_fans.size() + made.size());
    fanCells.reserve(m_fanCells.size() + 6 * made.size());
    std::size_t a = 0;
    std::size_t n = 0;
    while (a < m_fans.size() || n < made.size()) {
      const bool takeOld = n == made.size() || (a < m_fans.size() && m_fans[a].bond < made[n].bond);
      Fan fan = takeOld ? m_fans[a] : made[n];
      const auto first = static_cast<std::int32_t>(fanCells.size());
      if (takeOld) {
        fanCells.insert(fanCells.end(), m_fanCells.begin() + fan.first,
                        m_fanCells.begin() + fan.first + fan.count);
        ++a;
      } else {
        fanCells.insert(fanCells.end(), cells[n].begin(), cells[n].end());
        ++n;
      }
      fan.first = first;
      fans.push_back(fan);
    }
    m_fans = std::move(fans);
    m_fanCells = std::move(fanCells);
  }

  void emitBond(BondIndex b, const Fan& fan, std::int32_t midpoint, std::span<const Vec3> positions,
                const std::vector<Vec3>& points, std::vector<std::int32_t>& polygon,
                PrimitiveBlock& block) const {
    const dem::Bond& bond = m_decomposition.graph().bond(b);
    const Vec3 xa = positions[static_cast<std::size_t>(bond.first)];
    const Vec3 xb = positions[static_cast<std::size_t>(bond.second)];
    polygon.clear();
    const CellIndex* cells = m_fanCells.data() + fan.first;
    if (m_decomposition.dimension() == 2 || fan.count <= 1) {
      // 2D (a segment between the two triangles' centres) or a lone cell.
      for (std::uint8_t k = 0; k < fan.count; ++k) {
        polygon.push_back(m_pointOfCell[static_cast<std::size_t>(cells[k])]);
      }
      if (polygon.size() == 1) {
        polygon.insert(polygon.begin(), midpoint);
      }
      if (polygon.empty()) {
        block.vertices.push_back(midpoint);
        block.vertexTags.push_back(b);
      } else {
        block.lines.addRange(polygon.begin(), polygon.end());
        block.lineTags.push_back(b);
      }
      return;
    }
    if (fan.open) {
      polygon.push_back(midpoint);
    }
    for (std::uint8_t k = 0; k < fan.count; ++k) {
      polygon.push_back(m_pointOfCell[static_cast<std::size_t>(cells[k])]);
    }
    if (!fan.walked) {
      sortByAngle(polygon, points, 0.5 * (xa + xb), xb - xa);
    }
    // Normals along the bond, from its first particle to its second.
    if (dem::dot(polygonNormal(points, polygon.data(), polygon.size()), xb - xa) < 0.0) {
      std::reverse(polygon.begin(), polygon.end());
    }
    block.polygons.addRange(polygon.begin(), polygon.end());
    block.polygonTags.push_back(b);
  }

  // Midpoints were reserved for every broken bond; keep only those used.
  static void dropUnusedMidpoints(CrackMesh& out, std::int32_t base) {
    std::vector<std::int32_t> remap(out.points.size() - static_cast<std::size_t>(base), -1);
    auto visit = [&](std::vector<std::int32_t>& ids) {
      for (std::int32_t& id : ids) {
        if (id >= base) {
          auto& slot = remap[static_cast<std::size_t>(id - base)];
          if (slot < 0) {
            slot = 0;  // mark used
          }
        }
      }
    };
    visit(out.vertices);
    visit(out.lines.connectivity);
    visit(out.polygons.connectivity);
    std::int32_t next = base;
    for (std::size_t k = 0; k < remap.size(); ++k) {
      if (remap[k] == 0) {
        out.points[static_cast<std::size_t>(next)] = out.points[static_cast<std::size_t>(base) + k];
        remap[k] = next++;
      }
    }
    out.points.resize(static_cast<std::size_t>(next));
    auto apply = [&](std::vector<std::int32_t>& ids) {
      for (std::int32_t& id : ids) {
        if (id >= base) {
          id = remap[static_cast<std::size_t>(id - base)];
        }
      }
    };
    apply(out.vertices);
    apply(out.lines.connectivity);
    apply(out.polygons.connectivity);
  }

  LatticeDecomposition m_decomposition;
  std::vector<PrimitiveBlock> m_blocks;  // per-step scratch, kept for its buffers
  bool m_merge;
  std::vector<std::int32_t> m_pointOfCell;  // [cells] point of a (representative) cell, else -1
  std::vector<CellIndex> m_centreCells;     // point index -> representative cell
  std::vector<Fan> m_fans;                  // one per broken bond, by bond
  std::vector<CellIndex> m_fanCells;
};

}  // namespace

std::unique_ptr<CrackExtractor> makeCellCentre(const BondGraph& graph, int dimension,
                                               const ExtractOptions& options,
                                               const ExplicitCells* cells) {
  return std::make_unique<CellCentreExtractor>(graph, dimension, options, cells);
}

}  // namespace crackvis::cracks
