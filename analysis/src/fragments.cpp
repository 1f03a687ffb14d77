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

// Union-find root with path halving, here where the compiler can inline it:
// a step's fragments call it twice per intact bond.
inline std::int32_t rootOf(std::int32_t* parent, std::int32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
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
  std::int32_t* const up = parent.data();
  const std::size_t m = std::min(bonds.size(), bondState.size());
  for (std::size_t b = 0; b < m; ++b) {
    const auto i = bonds[b].first;
    const auto j = bonds[b].second;
    if (bondState[b] == 0 && i >= 0 && j >= 0 && static_cast<std::size_t>(i) < n &&
        static_cast<std::size_t>(j) < n) {
      const std::int32_t a = rootOf(up, i);
      const std::int32_t c = rootOf(up, j);
      if (a != c) {
        up[std::max(a, c)] = std::min(a, c);
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
    const auto root = static_cast<std::size_t>(rootOf(up, static_cast<std::int32_t>(i)));
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

void FragmentTracker::buildAdjacency(std::span<const dem::Bond> bonds, std::size_t particles) {
  m_firstBond.assign(particles + 1, 0);
  auto valid = [&](const dem::Bond& b) {
    return b.first >= 0 && b.second >= 0 && static_cast<std::size_t>(b.first) < particles &&
           static_cast<std::size_t>(b.second) < particles;
  };
  for (const dem::Bond& b : bonds) {
    if (valid(b)) {
      ++m_firstBond[static_cast<std::size_t>(b.first) + 1];
      ++m_firstBond[static_cast<std::size_t>(b.second) + 1];
    }
  }
  std::partial_sum(m_firstBond.begin(), m_firstBond.end(), m_firstBond.begin());
  m_bondsOf.assign(static_cast<std::size_t>(m_firstBond.back()), 0);
  std::vector<std::int32_t> next(m_firstBond.begin(), m_firstBond.end() - 1);
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    if (valid(bonds[b])) {
      for (const std::int32_t end : {bonds[b].first, bonds[b].second}) {
        m_bondsOf[static_cast<std::size_t>(next[static_cast<std::size_t>(end)]++)] =
            static_cast<std::int32_t>(b);
      }
    }
  }
  m_visitedAt.assign(particles, 0);
  m_label.assign(particles, 0);
  m_search = 0;
}

// Whether intact bonds still join the two ends of every new break: a flood
// from all their ends at once, breadth first over the intact bonds, each
// particle taking the label of the flood that reached it first; floods that
// meet join (a union-find over the labels). Stops as soon as every break's
// two ends share a label, or, undecided, after `budget` particles.
bool FragmentTracker::stillJoined(std::span<const dem::Bond> bonds,
                                  std::span<const std::uint8_t> bondState,
                                  std::span<const std::int32_t> fresh, std::size_t budget) {
  if (++m_search == 0) {  // the stamps wrapped: clear them
    std::fill(m_visitedAt.begin(), m_visitedAt.end(), 0);
    m_search = 1;
  }
  std::vector<std::int32_t> floods;  // union-find over the floods
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  m_queue.clear();
  auto floodOf = [&](std::int32_t particle) {
    const auto p = static_cast<std::size_t>(particle);
    if (m_visitedAt[p] != m_search) {
      m_visitedAt[p] = m_search;
      m_label[p] = static_cast<std::int32_t>(floods.size());
      floods.push_back(m_label[p]);
      m_queue.push_back(particle);
    }
    return m_label[p];
  };
  for (const std::int32_t b : fresh) {
    const dem::Bond& ends = bonds[static_cast<std::size_t>(b)];
    if (ends.first != ends.second) {
      pairs.emplace_back(floodOf(ends.first), floodOf(ends.second));
    }
  }
  auto allJoined = [&] {
    return std::all_of(pairs.begin(), pairs.end(), [&](const auto& pair) {
      return rootOf(floods.data(), pair.first) == rootOf(floods.data(), pair.second);
    });
  };
  std::size_t joinsSinceCheck = 0;
  for (std::size_t head = 0; head < m_queue.size(); ++head) {
    if (joinsSinceCheck > 0 && (head % 1024 == 0 || joinsSinceCheck >= pairs.size() / 4 + 1)) {
      if (allJoined()) {
        return true;
      }
      joinsSinceCheck = 0;
    }
    if (head >= budget) {
      return false;
    }
    const auto p = static_cast<std::size_t>(m_queue[head]);
    const std::int32_t label = m_label[p];
    for (std::int32_t k = m_firstBond[p]; k < m_firstBond[p + 1]; ++k) {
      const auto b = static_cast<std::size_t>(m_bondsOf[static_cast<std::size_t>(k)]);
      if (bondState[b] != 0) {
        continue;
      }
      const std::int32_t other =
          bonds[b].first == static_cast<std::int32_t>(p) ? bonds[b].second : bonds[b].first;
      const auto o = static_cast<std::size_t>(other);
      if (m_visitedAt[o] != m_search) {
        m_visitedAt[o] = m_search;
        m_label[o] = label;
        m_queue.push_back(other);
      } else {
        const std::int32_t a = rootOf(floods.data(), label);
        const std::int32_t c = rootOf(floods.data(), m_label[o]);
        if (a != c) {
          floods[static_cast<std::size_t>(std::max(a, c))] = std::min(a, c);
          ++joinsSinceCheck;
        }
      }
    }
  }
  return allJoined();  // every flood ran out: joined only if they met
}

const Fragments& FragmentTracker::update(std::span<const dem::Bond> bonds,
                                         std::span<const std::uint8_t> bondState,
                                         std::span<const double> radius, int dimension,
                                         const BondDiff* diff) {
  const bool known = m_valid && m_particles == radius.size() && bondState.size() == bonds.size();
  if (diff != nullptr && !diff->restart && known) {
    if (m_firstBond.size() != radius.size() + 1) {
      buildAdjacency(bonds, radius.size());
    }
    std::vector<std::int32_t> fresh;
    for (const std::int32_t b : diff->fresh) {
      const dem::Bond& ends = bonds[static_cast<std::size_t>(b)];
      if (ends.first >= 0 && ends.second >= 0 &&
          static_cast<std::size_t>(ends.first) < m_particles &&
          static_cast<std::size_t>(ends.second) < m_particles) {
        fresh.push_back(b);
      }
    }
    const std::size_t budget =
        std::min(m_particles, std::max(m_particles / 8, kFloodPerBreak * fresh.size()));
    const bool unchanged = stillJoined(bonds, bondState, fresh, budget);
    if (unchanged) {
      return m_fragments;
    }
  } else if (known && diff == nullptr && brokenKey(bondState) == m_brokenKey) {
    return m_fragments;
  }
  m_fragments = findFragments(bonds, bondState, radius, dimension);
  m_brokenKey = diff == nullptr ? brokenKey(bondState) : 0;
  m_particles = radius.size();
  m_valid = true;
  ++m_recomputations;
  return m_fragments;
}

}  // namespace crackvis::analysis
