// Fragments of the intact bond graph: an analytic case (a block cut into k
// slabs), an independent count by scipy, and the incremental tracker.
#include <fstream>
#include <random>
#include <sstream>

#include <fmt/format.h>

#include "analysis_fixtures.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"

using namespace crackvis;
using namespace crackvis::analysis;

namespace {

// The state of a block cut by the planes x = cuts[k] (between particle
// planes): every bond across one of them broken.
std::vector<std::uint8_t> cutIntoSlabs(const dem::LatticeBlock& block,
                                       const std::vector<double>& cuts) {
  const auto& bonds = block.lattice.bonds;
  std::vector<std::uint8_t> state(bonds.size(), 0);
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    const double a = block.positions[static_cast<std::size_t>(bonds[b].first)].x;
    const double c = block.positions[static_cast<std::size_t>(bonds[b].second)].x;
    for (double cut : cuts) {
      state[b] |= (a - cut) * (c - cut) < 0.0 ? 1 : 0;
    }
  }
  return state;
}

dem::LatticeBlock block(dem::LatticeKind kind, std::array<int, 3> sites) {
  dem::BlockSpec spec;
  spec.kind = kind;
  spec.sites = sites;
  spec.radius = 0.5;
  return dem::generateBlock(spec).value();
}

// Planes between the block's particle planes along x, k - 1 of them
// spread evenly.
std::vector<double> slabCuts(const dem::LatticeBlock& b, int slabs) {
  std::vector<double> xs;
  for (const dem::Vec3& p : b.positions) {
    xs.push_back(p.x);
  }
  std::sort(xs.begin(), xs.end());
  xs.erase(std::unique(xs.begin(), xs.end(), [](double a, double c) { return c - a < 1e-9; }),
           xs.end());
  std::vector<double> cuts;
  for (int k = 1; k < slabs; ++k) {
    const std::size_t at =
        xs.size() * static_cast<std::size_t>(k) / static_cast<std::size_t>(slabs);
    cuts.push_back(0.5 * (xs[at - 1] + xs[at]));
  }
  return cuts;
}

}  // namespace

TEST_CASE("a block cut into k slabs is exactly k fragments", "[analysis][fragments]") {
  for (const auto kind : {dem::LatticeKind::kFcc, dem::LatticeKind::kTriangular}) {
    const bool flat = kind == dem::LatticeKind::kTriangular;
    const dem::LatticeBlock b =
        block(kind, flat ? std::array<int, 3>{30, 12, 1} : dem::fccUnitCells(6, 3, 3));
    for (int slabs : {1, 2, 3, 5}) {
      INFO((flat ? "2D, " : "3D, ") << slabs << " slabs");
      const std::vector<std::uint8_t> state = cutIntoSlabs(b, slabCuts(b, slabs));
      const Fragments f = findFragments(b.lattice.bonds, state, b.lattice.radius, flat ? 2 : 3);
      CHECK(f.fragments.size() == static_cast<std::size_t>(slabs));
      std::size_t particles = 0;
      double volume = 0.0;
      for (const Fragment& piece : f.fragments) {
        particles += piece.particles;
        volume += piece.volume;
      }
      CHECK(particles == b.positions.size());
      CHECK(volume == Approx(f.totalVolume));
      CHECK(f.totalVolume ==
            Approx(static_cast<double>(b.positions.size()) * particleVolume(0.5, flat ? 2 : 3)));
      CHECK(f.largestShare() >= 1.0 / slabs - 1e-12);
      // Every particle's label is its fragment's rank, largest first.
      std::vector<std::size_t> counted(f.fragments.size(), 0);
      for (std::int32_t label : f.ofParticle) {
        ++counted.at(static_cast<std::size_t>(label));
      }
      for (std::size_t r = 0; r < counted.size(); ++r) {
        CHECK(counted[r] == f.fragments[r].particles);
      }
    }
  }
}

TEST_CASE("fragment counts and sizes agree with scipy's connected components",
          "[analysis][fragments]") {
  const dem::LatticeBlock b = block(dem::LatticeKind::kFcc, dem::fccUnitCells(5, 5, 5));
  std::mt19937_64 random(7);
  testing::TempDir dir;
  for (double broken : {0.0, 0.3, 0.55, 0.8}) {
    INFO("broken share " << broken);
    std::bernoulli_distribution breaks(broken);
    std::vector<std::uint8_t> state(b.lattice.bonds.size());
    for (auto& s : state) {
      s = breaks(random) ? 1 : 0;
    }
    const Fragments f = findFragments(b.lattice.bonds, state, b.lattice.radius, 3);

    const std::string graph = dir.file("graph.txt");
    {
      std::ofstream out(graph);
      const auto intact = static_cast<std::size_t>(std::count(state.begin(), state.end(), 0));
      out << b.positions.size() << ' ' << intact << '\n';
      for (std::size_t k = 0; k < state.size(); ++k) {
        if (state[k] == 0) {
          out << b.lattice.bonds[k].first << ' ' << b.lattice.bonds[k].second << '\n';
        }
      }
    }
    const auto scipy = testing::runProcess(
        {"/bin/sh", "-c",
         fmt::format("/usr/bin/python3 '{}' < '{}'", CRACKVIS_CONNECTED_COMPONENTS_SCRIPT, graph)});
    REQUIRE(scipy.exitCode == 0);
    std::istringstream answer(scipy.out);
    std::size_t count = 0;
    answer >> count;
    CHECK(f.fragments.size() == count);
    std::vector<std::size_t> sizes;
    for (std::size_t s; answer >> s;) {
      sizes.push_back(s);
    }
    std::vector<std::size_t> ours;
    for (const Fragment& piece : f.fragments) {
      ours.push_back(piece.particles);
    }
    std::sort(ours.rbegin(), ours.rend());
    CHECK(ours == sizes);
  }
}

TEST_CASE("fragments: dust is labelled apart, and the tracker reruns only when a bond broke",
          "[analysis][fragments]") {
  const dem::LatticeBlock b = block(dem::LatticeKind::kFcc, dem::fccUnitCells(4, 3, 3));
  std::vector<std::uint8_t> state = cutIntoSlabs(b, slabCuts(b, 2));
  // Free particle 0 from the rest: a one-particle fragment.
  for (std::size_t k = 0; k < state.size(); ++k) {
    if (b.lattice.bonds[k].first == 0 || b.lattice.bonds[k].second == 0) {
      state[k] = 1;
    }
  }
  const Fragments f = findFragments(b.lattice.bonds, state, b.lattice.radius, 3);
  REQUIRE(f.fragments.size() == 3);
  CHECK(f.countAtLeast(2) == 2);
  CHECK(f.fragments.back().particles == 1);
  const std::vector<double> labels = fragmentLabels(f, 2);
  CHECK(labels[0] == -1.0);
  CHECK(labels[1] >= 0.0);

  FragmentTracker tracker;
  tracker.update(b.lattice.bonds, state, b.lattice.radius, 3);
  tracker.update(b.lattice.bonds, state, b.lattice.radius, 3);
  CHECK(tracker.recomputations() == 1);
  const auto intact = std::find(state.begin(), state.end(), 0);
  REQUIRE(intact != state.end());
  *intact = 1;
  tracker.update(b.lattice.bonds, state, b.lattice.radius, 3);
  CHECK(tracker.recomputations() == 2);
}
