#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

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
  m_broken.assign(bondCount, 0);
  m_mid.assign(bondCount, {});
  m_axis.assign(bondCount, {});
  m_normal.assign(bondCount, {});
  m_window.assign(bondCount, 0);
  m_cells.clear();
}

std::uint64_t BondNormals::cellKey(dem::Vec3 p) const {
  return packCell(cellOf(p.x, m_radius), cellOf(p.y, m_radius), cellOf(p.z, m_radius));
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
        const auto found = m_cells.find(packCell(cx + dx, cy + dy, cz + dz));
        if (found == m_cells.end()) {
          continue;
        }
        for (std::int32_t b : found->second) {
          const dem::Vec3 d = m_mid[static_cast<std::size_t>(b)] - p;
          const double q = dem::dot(d, d) / r2;
          if (q < 1.0) {
            visit(static_cast<std::size_t>(b), (1.0 - q) * (1.0 - q));
          }
        }
      }
    }
  }
}

dem::Vec3 BondNormals::findNormal(std::size_t bond, std::uint32_t& window) const {
  // One pass over the grid collects the window; the sums run over it.
  thread_local std::vector<std::pair<std::size_t, double>> near;
  near.clear();
  forNear(m_mid[bond], [&](std::size_t b, double w) { near.emplace_back(b, w); });
  window = static_cast<std::uint32_t>(near.size());
  double weight = 0.0;
  dem::Vec3 mean{};
  for (const auto& [b, w] : near) {
    weight += w;
    mean = mean + w * m_mid[b];
  }
  dem::Vec3 axis;
  bool planar = false;
  if (near.size() >= (m_flat ? 2u : 3u) && weight > 0.0) {
    mean = (1.0 / weight) * mean;
    AxialTensor spread;
    for (const auto& [b, w] : near) {
      spread.add(m_mid[b] - mean, w);
    }
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
    AxialTensor directions;
    for (const auto& [b, w] : near) {
      directions.add(m_axis[b], w);
    }
    axis = directions.principalAxis();
  }
  return dem::dot(axis, m_axis[bond]) < 0.0 ? -1.0 * axis : axis;
}

void BondNormals::add(std::span<const dem::Bond> bonds, std::span<const std::int32_t> broken,
                      std::span<const dem::Vec3> reference) {
  if (m_broken.size() != bonds.size()) {
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
  std::vector<std::int32_t> fresh;
  for (std::int32_t id : broken) {
    const auto b = static_cast<std::size_t>(id);
    if (id < 0 || b >= bonds.size() || m_broken[b] != 0) {
      continue;
    }
    const auto i = static_cast<std::size_t>(bonds[b].first);
    const auto j = static_cast<std::size_t>(bonds[b].second);
    if (i >= reference.size() || j >= reference.size()) {
      continue;
    }
    m_broken[b] = 1;
    m_mid[b] = 0.5 * (reference[i] + reference[j]);
    const dem::Vec3 d0 = reference[j] - reference[i];
    const double length = dem::norm(d0);
    m_axis[b] = length > 0.0 ? (1.0 / length) * d0 : dem::Vec3{};
    m_cells[cellKey(m_mid[b])].push_back(id);
    fresh.push_back(id);
  }
  // The new bonds, and the broken bonds whose window they entered while that
  // window was still sparse: once a window holds kSettledWindow midpoints,
  // one more moves its plane little, and finding it again for every break
  // nearby was most of a step's cost on a large crack.
  std::vector<std::uint8_t> stale(m_broken.size(), 0);
  std::vector<std::size_t> again;
  for (std::int32_t id : fresh) {
    stale[static_cast<std::size_t>(id)] = 1;
    again.push_back(static_cast<std::size_t>(id));
  }
  for (std::int32_t id : fresh) {
    forNear(m_mid[static_cast<std::size_t>(id)], [&](std::size_t b, double) {
      if (stale[b] == 0 && m_window[b] < kSettledWindow) {
        stale[b] = 1;
        again.push_back(b);
      }
    });
  }
  for (std::size_t b : again) {
    m_normal[b] = findNormal(b, m_window[b]);
  }
  m_computed += again.size();
}

void BondNormals::update(std::span<const dem::Bond> bonds, std::span<const std::uint8_t> bondState,
                         std::span<const dem::Vec3> reference) {
  const std::size_t m = std::min(bonds.size(), bondState.size());
  if (m_broken.size() != bonds.size()) {
    reset(bonds.size());
  }
  std::vector<std::int32_t> fresh;
  for (std::size_t b = 0; b < m; ++b) {
    if (bondState[b] != 0 && m_broken[b] == 0) {
      fresh.push_back(static_cast<std::int32_t>(b));
    } else if (bondState[b] == 0 && m_broken[b] != 0) {
      // A bond healed: the viewer went back in time. Start over.
      reset(bonds.size());
      update(bonds, bondState, reference);
      return;
    }
  }
  add(bonds, fresh, reference);
}

}  // namespace crackvis::analysis
