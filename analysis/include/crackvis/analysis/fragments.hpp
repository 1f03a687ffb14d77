// Fragments: the connected pieces of the intact bond graph at a step (a
// particle without an intact bond is a fragment of its own). Each has a
// particle count and a volume from the radii (spheres in 3D; discs of unit
// thickness in 2D, so a 2D volume is an area in m^2).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <crackvis/analysis/bond_diff.hpp>
#include <crackvis/dem/model.hpp>

namespace crackvis::analysis {

struct Fragment {
  std::size_t particles = 0;
  double volume = 0.0;
};

struct Fragments {
  // Largest volume first (ties: more particles, then the lower first particle).
  std::vector<Fragment> fragments;
  // The rank in `fragments` of each particle's fragment [N].
  std::vector<std::int32_t> ofParticle;
  double totalVolume = 0.0;

  // The largest fragment's share of the total volume (0 without particles).
  double largestShare() const;
  // Fragments of at least `minParticles` particles: those that are no dust.
  std::size_t countAtLeast(std::size_t minParticles) const;
};

double particleVolume(double radius, int dimension);

Fragments findFragments(std::span<const dem::Bond> bonds, std::span<const std::uint8_t> bondState,
                        std::span<const double> radius, int dimension);

// Per-particle colour values: the fragment's rank, or -1 for particles of
// fragments smaller than `minParticles` (dust).
std::vector<double> fragmentLabels(const Fragments& fragments, std::size_t minParticles);

// Incremental across steps: bonds only break, so the union-find over the
// intact bonds runs again only when the set of broken bonds changed, and,
// where the new breaks are known (a BondDiff), only when they may have split
// a fragment: if the two ends of every new break are still joined by intact
// bonds, every piece is as it was. That is checked near the breaks, by
// floods over the intact bonds from all their ends at once that stop when
// each break's ends have met. Floods that have not decided after an eighth
// of the particles, or kFloodPerBreak per new break if that is more, leave
// it to the union-find; so does a true split, which they cannot tell from
// an undecided one.
class FragmentTracker {
 public:
  const Fragments& update(std::span<const dem::Bond> bonds, std::span<const std::uint8_t> bondState,
                          std::span<const double> radius, int dimension,
                          const BondDiff* diff = nullptr);
  const Fragments& current() const { return m_fragments; }
  // How often update() ran the union-find (for the benchmark and tests).
  std::size_t recomputations() const { return m_recomputations; }

  static constexpr std::size_t kFloodPerBreak = 32;

 private:
  bool stillJoined(std::span<const dem::Bond> bonds, std::span<const std::uint8_t> bondState,
                   std::span<const std::int32_t> fresh, std::size_t budget);
  void buildAdjacency(std::span<const dem::Bond> bonds, std::size_t particles);

  std::uint64_t m_brokenKey = 0;
  bool m_valid = false;
  std::size_t m_particles = 0;
  Fragments m_fragments;
  std::size_t m_recomputations = 0;
  // Each particle's bonds (CSR), built on the first search.
  std::vector<std::int32_t> m_firstBond;  // [N + 1]
  std::vector<std::int32_t> m_bondsOf;    // [2M]
  std::vector<std::uint32_t> m_visitedAt;
  std::vector<std::int32_t> m_label;  // the flood that reached a particle
  std::uint32_t m_search = 0;
  std::vector<std::int32_t> m_queue;
};

}  // namespace crackvis::analysis
