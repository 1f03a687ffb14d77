#include <algorithm>
#include <cstring>

#include <crackvis/analysis/bond_diff.hpp>

namespace crackvis::analysis {

const BondDiff& BondDiffer::update(std::span<const std::uint8_t> bondState) {
  m_diff.fresh.clear();
  if (m_first || m_seen.size() != bondState.size()) {
    m_seen.assign(bondState.begin(), bondState.end());
    m_diff.restart = true;
    m_diff.broken = static_cast<std::size_t>(
        std::count_if(bondState.begin(), bondState.end(), [](auto s) { return s != 0; }));
    m_first = false;
    return m_diff;
  }
  m_diff.restart = false;
  constexpr std::size_t kChunk = 64;
  for (std::size_t from = 0; from < bondState.size(); from += kChunk) {
    const std::size_t count = std::min(kChunk, bondState.size() - from);
    // Most chunks are as they were: compare them whole.
    if (std::memcmp(bondState.data() + from, m_seen.data() + from, count) == 0) {
      continue;
    }
    for (std::size_t b = from; b < from + count; ++b) {
      const bool broken = bondState[b] != 0;
      if (broken != (m_seen[b] != 0)) {
        if (broken) {
          m_diff.fresh.push_back(static_cast<std::int32_t>(b));
          ++m_diff.broken;
        } else {
          m_diff.restart = true;
          --m_diff.broken;
        }
      }
      m_seen[b] = bondState[b];
    }
  }
  return m_diff;
}

}  // namespace crackvis::analysis
