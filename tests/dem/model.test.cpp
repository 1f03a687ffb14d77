#include <cmath>
#include <type_traits>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <crackvis/dem/model.hpp>

using namespace crackvis;
using namespace crackvis::dem;

TEST_CASE("Type traits of the data model", "[dem]") {
  STATIC_REQUIRE(sizeof(Vec3) == 24);
  STATIC_REQUIRE(sizeof(Bond) == 8);
  STATIC_REQUIRE(std::is_trivially_copyable_v<Vec3>);
  STATIC_REQUIRE(std::is_trivially_copyable_v<Bond>);
  STATIC_REQUIRE(std::is_nothrow_move_constructible_v<Lattice>);
}

namespace {
Lattice square() {
  // Four particles on a unit square with its four edges as bonds.
  Lattice lattice;
  lattice.dimension = 2;
  lattice.radius = {0.5, 0.5, 0.5, 0.5};
  lattice.bonds = {{0, 1}, {1, 2}, {2, 3}, {3, 0}};
  lattice.strength = {1, 1, 1, 1};
  return lattice;
}
}  // namespace

TEST_CASE("validateLattice accepts a good lattice and names the first bad bond", "[dem]") {
  Lattice lattice = square();
  REQUIRE(validateLattice(lattice).isOk());

  SECTION("out of range") {
    lattice.bonds[2] = {2, 4};
    const Status status = validateLattice(lattice);
    REQUIRE(status.code() == StatusCode::kInvalidArgument);
    CHECK(status.message() ==
          "bond 2 joins particles 2 and 4: index out of range (N = 4 particles)");
  }
  SECTION("self-bond") {
    lattice.bonds[1] = {1, 1};
    CHECK(validateLattice(lattice).message() == "bond 1 is a self-bond of particle 1");
  }
  SECTION("duplicate in either order") {
    lattice.bonds[3] = {1, 0};
    CHECK(validateLattice(lattice).message() == "bond 3 duplicates bond 0 (particles 1 and 0)");
  }
  SECTION("of several duplicates, the smallest pair's two lowest bonds are named") {
    lattice.radius.assign(8, 0.5);
    lattice.bonds = {{5, 6}, {2, 3}, {6, 5}, {3, 2}, {2, 3}, {0, 7}, {7, 0}};
    lattice.strength.assign(lattice.bonds.size(), 1.0);
    // (0, 7) and (2, 3) come before (5, 6); (0, 7) is the smallest pair.
    CHECK(validateLattice(lattice).message() == "bond 6 duplicates bond 5 (particles 7 and 0)");
    lattice.bonds[6] = {1, 7};
    CHECK(validateLattice(lattice).message() == "bond 3 duplicates bond 1 (particles 3 and 2)");
    // One particle with two duplicated partners, the larger met first.
    lattice.bonds = {{0, 7}, {0, 5}, {7, 0}, {5, 0}, {1, 2}};
    lattice.strength.assign(lattice.bonds.size(), 1.0);
    CHECK(validateLattice(lattice).message() == "bond 3 duplicates bond 1 (particles 5 and 0)");
  }
  SECTION("a duplicate deep in a large list") {
    // A chain of 100,000 particles, each bonded to the next two; the last
    // particle's bond is repeated at the end of the list.
    constexpr int kParticles = 100'000;
    lattice.radius.assign(kParticles, 0.5);
    lattice.bonds.clear();
    for (int p = 0; p + 2 < kParticles; ++p) {
      lattice.bonds.push_back({p, p + 1});
      lattice.bonds.push_back({p + 2, p});
    }
    lattice.strength.assign(lattice.bonds.size(), 1.0);
    REQUIRE(validateLattice(lattice).isOk());
    const std::size_t original = lattice.bonds.size() - 1;  // {99997, 99999}
    lattice.bonds.push_back({kParticles - 3, kParticles - 1});
    lattice.strength.push_back(1.0);
    CHECK(validateLattice(lattice).message() ==
          fmt::format("bond {} duplicates bond {} (particles 99997 and 99999)",
                      lattice.bonds.size() - 1, original));
  }
  SECTION("non-positive radius") {
    lattice.radius[3] = 0.0;
    CHECK(validateLattice(lattice).message() ==
          "radius of particle 3 is 0, expected a positive finite value");
  }
  SECTION("strengths disagree with M") {
    lattice.strength.pop_back();
    CHECK(validateLattice(lattice).message() == "3 bond strengths for 4 bonds");
  }
  SECTION("dimension") {
    lattice.dimension = 4;
    CHECK(validateLattice(lattice).message() == "dimension is 4, expected 2 or 3");
  }
}

TEST_CASE("validateStep checks lengths, finiteness, 2D z and states", "[dem]") {
  const Lattice lattice = square();
  StepState step;
  step.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  step.bondState = {0, 1, 0, 0};
  REQUIRE(validateStep(lattice, step).isOk());
  CHECK(step.brokenBondCount() == 1);

  SECTION("NaN") {
    step.positions[2].y = std::nan("");
    CHECK(
        validateStep(lattice, step).message().starts_with("position of particle 2 is not finite"));
  }
  SECTION("2D with z") {
    step.positions[1].z = 0.25;
    CHECK(validateStep(lattice, step).message() ==
          "2D data set but particle 1 has z = 0.25 (expected 0)");
  }
  SECTION("bond states") {
    step.bondState[3] = 2;
    CHECK(validateStep(lattice, step).message() ==
          "state of bond 3 is 2, expected 0 (intact) or 1 (broken)");
  }
  SECTION("lengths") {
    step.bondState.push_back(0);
    CHECK(validateStep(lattice, step).message() == "5 bond states for M = 4 bonds");
  }
}
