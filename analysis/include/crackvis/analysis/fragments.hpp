// Fragments: the connected pieces of the intact bond graph at a step (a
// particle without an intact bond is a fragment of its own). Each has a
// particle count and a volume from the radii (spheres in 3D; discs of unit
// thickness in 2D, so a 2D volume is an area in m^2).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

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
// intact bonds runs again only when the set of broken bonds changed.
class FragmentTracker {
 public:
  const Fragments& update(std::span<const dem::Bond> bonds, std::span<const std::uint8_t> bondState,
                          std::span<const double> radius, int dimension);
  const Fragments& current() const { return m_fragments; }
  // How often update() ran the union-find (for the benchmark and tests).
  std::size_t recomputations() const { return m_recomputations; }

 private:
  std::uint64_t m_brokenKey = 0;
  bool m_valid = false;
  std::size_t m_particles = 0;
  Fragments m_fragments;
  std::size_t m_recomputations = 0;
};

}  // namespace crackvis::analysis
