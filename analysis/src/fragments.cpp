#include <algorithm>
#include <numbers>
#include <numeric>

#include <crackvis/analysis/fragments.hpp>
#include <crackvis/cracks/surface_primitives.hpp>

namespace crackvis::analysis {

namespace {

// A key of the set of broken bonds: their count and a hash of their indices.
std::uint64_t brokenKey(std::span<const std::uint8_t> bondState) {
  std::uint64_t hash = 0;
  std::uint64_t count = 0;
  for (std::size_t b = 0; b < bondState.size(); ++b) {
    if (bondState[b] != 0) {
      std::uint64_t x = b + 0x9E3779B97F4A7C15ull;  // splitmix64's finaliser
      x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
      x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
      hash += x ^ (x >> 31);
      ++count;
    }
  }
  return hash ^ (count * 0x2545F4914F6CDD1Dull);
}

}  // namespace

double Fragments::largestShare() const {
  return fragments.empty() || totalVolume <= 0.0 ? 0.0 : fragments.front().volume / totalVolume;
}

std::size_t Fragments::countAtLeast(std::size_t minParticles) const {
  return static_cast<std::size_t>(std::count_if(
      fragments.begin(), fragments.end(),
      [&](const Fragment& f) { return f.particles >= std::max<std::size_t>(minParticles, 1); }));
}

double particleVolume(double radius, int dimension) {
  return dimension == 2 ? std::numbers::pi * radius * radius
                        : 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;
}

Fragments findFragments(std::span<const dem::Bond> bonds, std::span<const std::uint8_t> bondState,
                        std::span<const double> radius, int dimension) {
  const std::size_t n = radius.size();
  std::vector<std::int32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t b = 0; b < bonds.size() && b < bondState.size(); ++b) {
    const auto i = bonds[b].first;
    const auto j = bonds[b].second;
    if (bondState[b] == 0 && i >= 0 && j >= 0 && static_cast<std::size_t>(i) < n &&
        static_cast<std::size_t>(j) < n) {
      const std::int32_t a = cracks::findRoot(parent, i);
      const std::int32_t c = cracks::findRoot(parent, j);
      if (a != c) {
        parent[static_cast<std::size_t>(std::max(a, c))] = std::min(a, c);
      }
    }
  }
  // Roots are each piece's lowest particle; number them in particle order.
  std::vector<std::int32_t> piece(n, -1);
  std::vector<Fragment> found;
  std::vector<std::size_t> firstParticle;
  Fragments out;
  out.ofParticle.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto root =
        static_cast<std::size_t>(cracks::findRoot(parent, static_cast<std::int32_t>(i)));
    if (piece[root] < 0) {
      piece[root] = static_cast<std::int32_t>(found.size());
      found.push_back({});
      firstParticle.push_back(i);
    }
    Fragment& f = found[static_cast<std::size_t>(piece[root])];
    const double v = particleVolume(radius[i], dimension);
    ++f.particles;
    f.volume += v;
    out.totalVolume += v;
    out.ofParticle[i] = piece[root];
  }
  std::vector<std::size_t> order(found.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (found[a].volume != found[b].volume) {
      return found[a].volume > found[b].volume;
    }
    if (found[a].particles != found[b].particles) {
      return found[a].particles > found[b].particles;
    }
    return firstParticle[a] < firstParticle[b];
  });
  std::vector<std::int32_t> rank(found.size());
  for (std::size_t r = 0; r < order.size(); ++r) {
    rank[order[r]] = static_cast<std::int32_t>(r);
    out.fragments.push_back(found[order[r]]);
  }
  for (std::int32_t& label : out.ofParticle) {
    label = rank[static_cast<std::size_t>(label)];
  }
  return out;
}

std::vector<double> fragmentLabels(const Fragments& fragments, std::size_t minParticles) {
  std::vector<double> labels(fragments.ofParticle.size());
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const auto rank = static_cast<std::size_t>(fragments.ofParticle[i]);
    labels[i] = fragments.fragments[rank].particles >= minParticles
                    ? static_cast<double>(fragments.ofParticle[i])
                    : -1.0;
  }
  return labels;
}

const Fragments& FragmentTracker::update(std::span<const dem::Bond> bonds,
                                         std::span<const std::uint8_t> bondState,
                                         std::span<const double> radius, int dimension) {
  const std::uint64_t key = brokenKey(bondState);
  if (!m_valid || key != m_brokenKey || m_particles != radius.size()) {
    m_fragments = findFragments(bonds, bondState, radius, dimension);
    m_brokenKey = key;
    m_particles = radius.size();
    m_valid = true;
    ++m_recomputations;
  }
  return m_fragments;
}

}  // namespace crackvis::analysis
