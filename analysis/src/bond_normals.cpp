#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>

#include <crackvis/analysis/bond_normals.hpp>
#include <crackvis/analysis/tensor.hpp>

namespace crackvis::analysis {

namespace {

std::int64_t cellOf(double v, double size) {
  return static_cast<std::int64_t>(std::floor(v / size));
}

std::uint64_t packCell(std::int64_t x, std::int64_t y, std::int64_t z) {
  const auto part = [](std::int64_t v) { return static_cast<std::uint64_t>(v) & 0x1FFFFFu; };
  return part(x) | (part(y) << 21) | (part(z) << 42);
}

}  // namespace

void BondNormals::reset(std::size_t bondCount) {
  m_index.assign(bondCount, -1);
  m_mid.clear();
  m_axis.clear();
  m_normal.clear();
  m_window.clear();
  m_stale.clear();
  m_sumsOf.clear();
  m_sums.clear();
  m_freeSums.clear();
  m_slots.assign(1024, Slot{});
  m_lists.clear();
}

std::uint64_t BondNormals::cellKey(dem::Vec3 p) const {
  return packCell(cellOf(p.x, m_radius), cellOf(p.y, m_radius), cellOf(p.z, m_radius));
}

namespace {

std::size_t slotHash(std::uint64_t key) {
  key ^= key >> 33;
  key *= 0xFF51AFD7ED558CCDull;
  key ^= key >> 33;
  return static_cast<std::size_t>(key);
}

}  // namespace

const std::vector<BondNormals::Entry>* BondNormals::findCell(std::uint64_t key) const {
  const std::size_t mask = m_slots.size() - 1;
  for (std::size_t k = slotHash(key) & mask;; k = (k + 1) & mask) {
    if (m_slots[k].key == key) {
      return &m_lists[static_cast<std::size_t>(m_slots[k].list)];
    }
    if (m_slots[k].key == kNoCell) {
      return nullptr;
    }
  }
}

std::vector<BondNormals::Entry>& BondNormals::cell(std::uint64_t key) {
  if (2 * (m_lists.size() + 1) > m_slots.size()) {  // keep the table at most half full
    std::vector<Slot> old(2 * m_slots.size(), Slot{});
    old.swap(m_slots);
    for (const Slot& slot : old) {
      if (slot.key != kNoCell) {
        std::size_t k = slotHash(slot.key) & (m_slots.size() - 1);
        while (m_slots[k].key != kNoCell) {
          k = (k + 1) & (m_slots.size() - 1);
        }
        m_slots[k] = slot;
      }
    }
  }
  const std::size_t mask = m_slots.size() - 1;
  std::size_t k = slotHash(key) & mask;
  while (m_slots[k].key != key && m_slots[k].key != kNoCell) {
    k = (k + 1) & mask;
  }
  if (m_slots[k].key == kNoCell) {
    m_slots[k] = {key, static_cast<std::int32_t>(m_lists.size())};
    m_lists.emplace_back();
  }
  return m_lists[static_cast<std::size_t>(m_slots[k].list)];
}

template <typename Visit>
void BondNormals::forNear(dem::Vec3 p, Visit&& visit) const {
  const std::int64_t cx = cellOf(p.x, m_radius);
  const std::int64_t cy = cellOf(p.y, m_radius);
  const std::int64_t cz = cellOf(p.z, m_radius);
  const double r2 = m_radius * m_radius;
  for (std::int64_t dx = -1; dx <= 1; ++dx) {
    for (std::int64_t dy = -1; dy <= 1; ++dy) {
      for (std::int64_t dz = m_flat ? 0 : -1; dz <= (m_flat ? 0 : 1); ++dz) {
        const std::vector<Entry>* entries = findCell(packCell(cx + dx, cy + dy, cz + dz));
        if (entries == nullptr) {
          continue;
        }
        for (const Entry& entry : *entries) {
          const dem::Vec3 d = entry.mid - p;
          const double q = dem::dot(d, d) / r2;
          if (q < 1.0) {
            visit(static_cast<std::size_t>(entry.index), (1.0 - q) * (1.0 - q));
          }
        }
      }
    }
  }
}

dem::Vec3 BondNormals::normalOf(std::size_t k, const WindowSums& sums) const {
  dem::Vec3 axis;
  bool planar = false;
  if (sums.count >= (m_flat ? 2u : 3u) && sums.weight > 0.0) {
    // The spread about the weighted mean: sum w d d^T - W mean mean^T, of
    // offsets from the bond's own midpoint (at most R long: little cancellation).
    const dem::Vec3 mean = (1.0 / sums.weight) * sums.offset;
    AxialTensor spread = sums.spread;
    spread.add(mean, -sums.weight);
    const double total = spread.trace();
    if (m_flat) {
      spread.addZ(total + 1.0);  // z is never the normal of a 2D crack
    }
    axis = spread.smallestAxis();
    const double across = spread.along(axis);
    const double inPlane = m_flat ? total - across : (total - across) / 2.0;
    planar = across < 0.1 * inPlane;  // far less spread across than along
  }
  if (!planar) {
    axis = sums.directions.principalAxis();
  }
  return dem::dot(axis, m_axis[k]) < 0.0 ? -1.0 * axis : axis;
}

void BondNormals::add(std::span<const dem::Bond> bonds, std::span<const std::int32_t> broken,
                      std::span<const dem::Vec3> reference) {
  if (m_index.size() != bonds.size()) {
    reset(bonds.size());
  }
  if (m_radius <= 0.0) {
    double sum = 0.0;
    for (const dem::Bond& b : bonds) {
      sum += dem::norm(reference[static_cast<std::size_t>(b.second)] -
                       reference[static_cast<std::size_t>(b.first)]);
    }
    m_radius = bonds.empty() ? 1.0 : 3.0 * sum / static_cast<double>(bonds.size());
  }
  const std::size_t first = m_mid.size();  // the new bonds' dense indices follow
  for (std::int32_t id : broken) {
    const auto b = static_cast<std::size_t>(id);
    if (id < 0 || b >= bonds.size() || m_index[b] >= 0) {
      continue;
    }
    const auto i = static_cast<std::size_t>(bonds[b].first);
    const auto j = static_cast<std::size_t>(bonds[b].second);
    if (i >= reference.size() || j >= reference.size()) {
      continue;
    }
    const auto k = static_cast<std::int32_t>(m_mid.size());
    m_index[b] = k;
    const dem::Vec3 mid = 0.5 * (reference[i] + reference[j]);
    const dem::Vec3 d0 = reference[j] - reference[i];
    const double length = dem::norm(d0);
    m_mid.push_back(mid);
    m_axis.push_back(length > 0.0 ? (1.0 / length) * d0 : dem::Vec3{});
    m_normal.emplace_back();
    m_window.push_back(0);
    m_stale.push_back(0);
    if (m_freeSums.empty()) {
      m_sumsOf.push_back(static_cast<std::int32_t>(m_sums.size()));
      m_sums.emplace_back();
    } else {
      m_sumsOf.push_back(m_freeSums.back());
      m_freeSums.pop_back();
      m_sums[static_cast<std::size_t>(m_sumsOf.back())] = WindowSums{};
    }
    cell(cellKey(mid)).push_back({mid, k});
  }
  // The new bonds, and the broken bonds whose window they entered while that
  // window was still sparse: once a window holds kSettledWindow midpoints,
  // one more moves its plane little, and finding it again for every break
  // nearby was most of a step's cost on a large crack. One search per new
  // bond sums its own window and adds it to the sparse windows it entered.
  // The searches run on all cores in blocks; what they add to the old
  // windows is added after, block by block, so every sum is taken in the
  // same order on any number of cores.
  struct Entered {
    std::size_t window;  // the old bond whose window a new one entered
    std::size_t by;      // the new bond
    double weight;
  };
  const std::size_t blocks = (m_mid.size() - first + kSearchBlock - 1) / kSearchBlock;
  std::vector<std::vector<Entered>> entered(blocks);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t block) {
    const std::size_t end = std::min(m_mid.size(), first + (block + 1) * kSearchBlock);
    for (std::size_t k = first + block * kSearchBlock; k < end; ++k) {
      WindowSums& own = sumsOf(k);
      forNear(m_mid[k], [&](std::size_t b, double w) {
        own.add(m_mid[b] - m_mid[k], w, m_axis[b]);
        if (b < first && m_sumsOf[b] >= 0) {
          entered[block].push_back({b, k, w});
        }
      });
    }
  });
  std::vector<std::size_t> found(m_mid.size() - first);
  std::iota(found.begin(), found.end(), first);
  for (const std::vector<Entered>& list : entered) {
    for (const Entered& e : list) {
      sumsOf(e.window).add(m_mid[e.by] - m_mid[e.window], e.weight, m_axis[e.by]);
      if (m_stale[e.window] == 0) {
        m_stale[e.window] = 1;
        found.push_back(e.window);
      }
    }
  }
  // The planes on all cores; then the settled windows give their sums back.
  tbb::parallel_for(std::size_t{0}, found.size(), [&](std::size_t n) {
    const std::size_t k = found[n];
    m_normal[k] = normalOf(k, sumsOf(k));
    m_window[k] = sumsOf(k).count;
  });
  for (std::size_t k : found) {
    m_stale[k] = 0;
    if (m_window[k] >= kSettledWindow) {
      m_freeSums.push_back(m_sumsOf[k]);
      m_sumsOf[k] = -1;
    }
  }
  m_computed += found.size();
}

void BondNormals::update(std::span<const dem::Bond> bonds, std::span<const std::uint8_t> bondState,
                         std::span<const dem::Vec3> reference) {
  const std::size_t m = std::min(bonds.size(), bondState.size());
  if (m_index.size() != bonds.size()) {
    reset(bonds.size());
  }
  std::vector<std::int32_t> fresh;
  for (std::size_t b = 0; b < m; ++b) {
    if (bondState[b] != 0 && m_index[b] < 0) {
      fresh.push_back(static_cast<std::int32_t>(b));
    } else if (bondState[b] == 0 && m_index[b] >= 0) {
      // A bond healed: the viewer went back in time. Start over.
      reset(bonds.size());
      update(bonds, bondState, reference);
      return;
    }
  }
  add(bonds, fresh, reference);
}

void BondNormals::update(std::span<const dem::Bond> bonds, const BondDiff& diff,
                         std::span<const std::uint8_t> bondState,
                         std::span<const dem::Vec3> reference) {
  if (diff.restart || m_index.size() != bonds.size()) {
    update(bonds, bondState, reference);
    return;
  }
  add(bonds, diff.fresh, reference);
}

}  // namespace crackvis::analysis
