// The crack's local normal at each broken bond, in the reference
// configuration, kept across steps.
//
// A lattice's crack surface is made of the faces of single bonds, which
// zig-zag about the crack: on FCC the faces of a crack along a cube plane
// lean 45 degrees off it, and a pure tension opening measured along them
// would read as half slip; and the faces lean further as the crack opens.
// The crack itself runs through the midpoints of its broken bonds (exactly,
// on a lattice: a bond across a lattice plane has its midpoint on it). A
// broken bond's normal is therefore the plane through the reference
// midpoints of the broken bonds within R of its own, each weighted by
// (1 - (r/R)^2)^2 so that the zig-zag entering the window at its edge does
// not tilt it; where those make no plane (a lone break, a thread of a few),
// the principal axis of their reference directions. It is oriented along the
// bond (n . d0 > 0). R: three mean bond lengths unless given.
//
// Incremental: a step's new breaks get their normals, and the broken bonds
// within R of a new one are found again while their window is sparse (fewer
// than kSettledWindow midpoints), from sums each new break adds itself to;
// a bond that heals (a viewer stepping back) starts the set over.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <crackvis/analysis/bond_diff.hpp>
#include <crackvis/analysis/tensor.hpp>
#include <crackvis/dem/model.hpp>

namespace crackvis::analysis {

class BondNormals {
 public:
  // `radius` <= 0: three times the mean reference length of the bonds.
  explicit BondNormals(int dimension, double radius = 0.0)
      : m_flat(dimension == 2), m_radius(radius) {}

  // Brings the set of broken bonds to `bondState` [M].
  void update(std::span<const dem::Bond> bonds, std::span<const std::uint8_t> bondState,
              std::span<const dem::Vec3> reference);
  // The same, where the bonds new since the last update are known (`diff`,
  // of these states).
  void update(std::span<const dem::Bond> bonds, const BondDiff& diff,
              std::span<const std::uint8_t> bondState, std::span<const dem::Vec3> reference);
  // Adds broken bonds (ids into `bonds`), finding their normals.
  void add(std::span<const dem::Bond> bonds, std::span<const std::int32_t> broken,
           std::span<const dem::Vec3> reference);

  // The unit normal of a broken bond (zero for one not in the set).
  dem::Vec3 normal(std::size_t bond) const {
    return bond < m_index.size() && m_index[bond] >= 0
               ? m_normal[static_cast<std::size_t>(m_index[bond])]
               : dem::Vec3{};
  }
  double radius() const { return m_radius; }
  // How many normals were found (again) in all: the incremental work.
  std::size_t computed() const { return m_computed; }
  // The midpoints in a broken bond's window when its normal was last found
  // (0 for one not in the set); from kSettledWindow on it is found no more.
  std::uint32_t window(std::size_t bond) const {
    return bond < m_index.size() && m_index[bond] >= 0
               ? m_window[static_cast<std::size_t>(m_index[bond])]
               : 0;
  }
  static constexpr std::uint32_t kSettledWindow = 24;
  // New breaks per block of add()'s searches on all cores.
  static constexpr std::size_t kSearchBlock = 256;

 private:
  void reset(std::size_t bondCount);
  std::uint64_t cellKey(dem::Vec3 p) const;
  template <typename Visit>
  void forNear(dem::Vec3 p, Visit&& visit) const;
  // What a window's plane is found from, summed while the window is sparse:
  // the midpoints' weights and offsets from the bond's own midpoint, their
  // second moments, and those of the reference directions. A new break adds
  // itself to the sparse windows it enters, so none is searched again.
  struct WindowSums {
    std::uint32_t count = 0;
    double weight = 0.0;
    dem::Vec3 offset{};
    AxialTensor spread;
    AxialTensor directions;
    void add(dem::Vec3 d, double w, dem::Vec3 axis) {
      ++count;
      weight += w;
      offset = offset + w * d;
      spread.add(d, w);
      directions.add(axis, w);
    }
  };
  // The normal of broken bond k (its index among the broken ones) from its
  // window's sums.
  dem::Vec3 normalOf(std::size_t k, const WindowSums& sums) const;
  WindowSums& sumsOf(std::size_t k) { return m_sums[static_cast<std::size_t>(m_sumsOf[k])]; }

  bool m_flat;
  double m_radius;
  // Per bond its index among the broken ones (-1: intact) [M]; per broken
  // bond, in the order they broke, what its normal is found from [K].
  std::vector<std::int32_t> m_index;
  std::vector<dem::Vec3> m_mid;   // reference midpoints
  std::vector<dem::Vec3> m_axis;  // unit reference directions
  std::vector<dem::Vec3> m_normal;
  std::vector<std::uint32_t> m_window;  // midpoints in the window when last found
  std::vector<std::uint8_t> m_stale;    // scratch of add(), all 0 between calls
  std::vector<std::int32_t> m_sumsOf;   // [K] into m_sums; -1 once the window settled
  std::vector<WindowSums> m_sums;       // of the sparse windows, slots reused
  std::vector<std::int32_t> m_freeSums;
  // The broken bonds' midpoints by grid cell (of size R), kept beside their
  // ids so a window's search reads each cell's entries in a row.
  struct Entry {
    dem::Vec3 mid;
    std::int32_t index;  // among the broken bonds
  };
  // Open addressing over the cells' keys (a power of two of slots).
  struct Slot {
    std::uint64_t key = kNoCell;
    std::int32_t list = -1;  // into m_lists
  };
  static constexpr std::uint64_t kNoCell = ~std::uint64_t{0};
  const std::vector<Entry>* findCell(std::uint64_t key) const;
  std::vector<Entry>& cell(std::uint64_t key);
  std::vector<Slot> m_slots = std::vector<Slot>(1024);
  std::vector<std::vector<Entry>> m_lists;
  std::size_t m_computed = 0;
};

}  // namespace crackvis::analysis
