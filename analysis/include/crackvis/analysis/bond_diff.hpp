// What changed in the bond states since the last step, found once per step
// for the analyses that follow breaks (normals, fragments, modes), so that
// none of them reads all M bond states again.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace crackvis::analysis {

struct BondDiff {
  // Broken now, intact at the last step, in bond order.
  std::vector<std::int32_t> fresh;
  // The first step, a bond that healed (a viewer going back) or another
  // bond count: what follows the breaks starts over from the states.
  bool restart = true;
  std::size_t broken = 0;  // bonds broken now
};

class BondDiffer {
 public:
  const BondDiff& update(std::span<const std::uint8_t> bondState);
  const BondDiff& current() const { return m_diff; }

 private:
  std::vector<std::uint8_t> m_seen;  // the last step's states
  bool m_first = true;
  BondDiff m_diff;
};

}  // namespace crackvis::analysis
