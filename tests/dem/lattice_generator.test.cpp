#include <algorithm>
#include <cmath>

#include <catch2/catch.hpp>

#include <crackvis/dem/lattice_generator.hpp>

using namespace crackvis;
using namespace crackvis::dem;

namespace {

LatticeBlock generate(LatticeKind kind, std::array<int, 3> sites, double jitter = 0.0,
                      std::uint64_t seed = 1) {
  BlockSpec spec;
  spec.kind = kind;
  spec.sites = sites;
  spec.radius = 0.5;  // d = 1
  spec.jitter = jitter;
  spec.seed = seed;
  auto block = generateBlock(spec);
  REQUIRE(block.isOk());
  REQUIRE(validateLattice(block->lattice).isOk());
  return std::move(block).value();
}

// A particle is interior when every lattice site within one bond length of it
// exists: it is at least `margin` from every face of the block.
bool isInterior(Vec3 p, Vec3 extent, double radius, double margin, int dimension) {
  auto inside = [&](double v, double hi) {
    return v - radius >= margin - 1e-9 && hi - radius - v >= margin - 1e-9;
  };
  return inside(p.x, extent.x) && inside(p.y, extent.y) &&
         (dimension == 2 || inside(p.z, extent.z));
}

}  // namespace

TEST_CASE("FCC block of n x n x n cubic cells has the hand-derived counts", "[dem][lattice]") {
  // Sites (i, j, k), 0 <= i, j, k <= 2n, with i + j + k even:
  //   N = (n+1)^3 corners + 3 n^2 (n+1) face centres.
  // Bonds join sites one step apart along two axes, e.g. (1, 1, 0). For that
  // direction i, j range over 2n values each and k over 2n+1; the (i, j) with
  // i + j even (2n^2 of them) pair with the n+1 even k, the odd ones (2n^2)
  // with the n odd k: 2n^2 (2n+1) bonds. Six such directions:
  //   M = 12 n^2 (2n+1).
  const int n = GENERATE(1, 2, 3, 4);
  const LatticeBlock block = generate(LatticeKind::kFcc, fccUnitCells(n, n, n));
  const auto expectedN = static_cast<size_t>((n + 1) * (n + 1) * (n + 1) + 3 * n * n * (n + 1));
  const auto expectedM = static_cast<size_t>(12 * n * n * (2 * n + 1));
  CHECK(block.lattice.particleCount() == expectedN);
  CHECK(block.lattice.bondCount() == expectedM);
  CHECK(block.lattice.dimension == 3);
  // The cube's edge is n lattice constants a = d sqrt(2) plus one diameter.
  CHECK(block.extent.x == Approx(n * std::sqrt(2.0) + 1.0));
}

TEST_CASE("bonds are exactly the pairs at distance d, found by brute force", "[dem][lattice]") {
  const auto kind = GENERATE(LatticeKind::kFcc, LatticeKind::kHcp, LatticeKind::kTriangular);
  const LatticeBlock block = generate(kind, {6, 5, 4});
  std::vector<Bond> expected;
  const auto& p = block.positions;
  for (size_t i = 0; i < p.size(); ++i) {
    for (size_t j = i + 1; j < p.size(); ++j) {
      const double length = norm(p[j] - p[i]);
      REQUIRE((length > 1.0 + 1e-9 || length > 1.0 - 1e-9));  // nothing closer than d
      if (length < 1.0 + 1e-9) {
        expected.push_back({static_cast<ParticleIndex>(i), static_cast<ParticleIndex>(j)});
      }
    }
  }
  CHECK(block.lattice.bonds == expected);
}

TEST_CASE("interior coordination is 12 in FCC and HCP and 6 in the triangular lattice",
          "[dem][lattice]") {
  struct Case {
    LatticeKind kind;
    std::array<int, 3> sites;
    int expected;
    double margin;  // distance from the faces beyond which all neighbours exist
  };
  // HCP and triangular rows are staggered by d/2, so their faces are ragged:
  // half a bond more margin there.
  const Case c = GENERATE(Case{LatticeKind::kFcc, {9, 9, 9}, 12, 1.0},
                          Case{LatticeKind::kHcp, {8, 8, 7}, 12, 1.5},
                          Case{LatticeKind::kTriangular, {10, 9, 1}, 6, 1.5});
  const LatticeBlock block = generate(c.kind, c.sites);
  const std::vector<int> count = coordination(block.lattice);
  int interior = 0;
  for (size_t i = 0; i < count.size(); ++i) {
    if (isInterior(block.positions[i], block.extent, 0.5, c.margin, block.lattice.dimension)) {
      ++interior;
      REQUIRE(count[i] == c.expected);
    }
    REQUIRE(count[i] <= c.expected);
  }
  CHECK(interior > 10);
}

TEST_CASE("HCP and triangular blocks have the expected site and bond counts", "[dem][lattice]") {
  // Triangular, nx per row and ny rows, odd rows shifted by d/2: ny (nx-1)
  // bonds along rows and 2 nx - 1 between each pair of adjacent rows.
  const LatticeBlock tri = generate(LatticeKind::kTriangular, {7, 4, 1});
  CHECK(tri.lattice.particleCount() == 28);
  CHECK(tri.lattice.bondCount() == static_cast<size_t>(4 * 6 + 3 * 13));
  CHECK(tri.lattice.dimension == 2);
  for (const Vec3& p : tri.positions) {
    REQUIRE(p.z == 0.0);
  }
  const LatticeBlock hcp = generate(LatticeKind::kHcp, {5, 4, 3});
  CHECK(hcp.lattice.particleCount() == 60);
  // Each layer has the triangular bonds; layers are bonded too.
  CHECK(hcp.lattice.bondCount() > static_cast<size_t>(3 * (4 * 4 + 3 * 9)));
}

TEST_CASE("jitter is seeded, bounded and leaves the topology alone", "[dem][lattice]") {
  const LatticeBlock exact = generate(LatticeKind::kFcc, {5, 5, 5});
  const LatticeBlock a = generate(LatticeKind::kFcc, {5, 5, 5}, 0.2, 42);
  const LatticeBlock b = generate(LatticeKind::kFcc, {5, 5, 5}, 0.2, 42);
  const LatticeBlock c = generate(LatticeKind::kFcc, {5, 5, 5}, 0.2, 43);
  CHECK(a.positions == b.positions);
  CHECK(a.positions != c.positions);
  CHECK(a.lattice.bonds == exact.lattice.bonds);
  double largest = 0.0;
  for (size_t i = 0; i < a.positions.size(); ++i) {
    const Vec3 d = a.positions[i] - exact.positions[i];
    largest = std::max({largest, std::abs(d.x), std::abs(d.y), std::abs(d.z)});
  }
  CHECK(largest <= 0.2 * 0.5);
  CHECK(largest > 0.05);  // it did move them
}

TEST_CASE("sitesForBox fills a box without spheres leaving it", "[dem][lattice]") {
  const auto kind = GENERATE(LatticeKind::kFcc, LatticeKind::kHcp, LatticeKind::kTriangular);
  const Vec3 box{0.211, 0.1, kind == LatticeKind::kTriangular ? 0.0 : 0.1};
  BlockSpec spec;
  spec.kind = kind;
  spec.radius = 0.004;
  spec.sites = sitesForBox(kind, box, spec.radius);
  auto block = generateBlock(spec);
  REQUIRE(block.isOk());
  CHECK(block->extent.x <= box.x + 1e-12);
  CHECK(block->extent.y <= box.y + 1e-12);
  CHECK(block->extent.z <= box.z + 1e-12);
  // One more site along x would not fit.
  spec.sites[0] += 1;
  CHECK(generateBlock(spec)->extent.x > box.x);
}

TEST_CASE("generateBlock refuses nonsense with a clear message", "[dem][lattice]") {
  BlockSpec spec;
  spec.radius = -1.0;
  CHECK(generateBlock(spec).status().message() == "radius must be positive, got -1");
  spec.radius = 1.0;
  spec.jitter = 0.7;
  CHECK(generateBlock(spec).status().message().starts_with("jitter must be in [0, 0.5)"));
  spec.jitter = 0.0;
  spec.sites = {3, 0, 3};
  CHECK(generateBlock(spec).status().message() == "sites along axis y must be >= 1, got 0");
  CHECK(parseLatticeKind("bcc").status().message() ==
        "unknown lattice 'bcc' (expected fcc, hcp or triangular)");
}
