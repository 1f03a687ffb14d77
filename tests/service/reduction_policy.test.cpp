// How an interacting session's frames are drawn (ReductionPolicy), fed
// modelled render times and turn waits: the sharpest factor that holds the
// budget, a factor that does not pay off given up, the limits kept, the wait
// for a render turn counted, and coarse stand-ins only while frames meet others.
#include "reduction_policy.hpp"

#include <algorithm>
#include <functional>

#include <catch2/catch.hpp>

namespace crackvis::service {
namespace {

SessionLimits limitsOf(double budgetMs, int maxReduction) {
  SessionLimits limits;
  limits.interactiveFrameMs = budgetMs;
  limits.maxReduction = maxReduction;
  return limits;
}

// Renders `frames` reduced frames whose time at factor f is renderMs(f);
// returns the factors used, in order.
std::vector<int> run(ReductionPolicy& policy, const std::function<double(int)>& renderMs,
                     int frames) {
  std::vector<int> factors;
  for (int k = 0; k < frames; ++k) {
    factors.push_back(policy.factor());
    policy.adapt(renderMs(policy.factor()), 0.0, false, false);
  }
  return factors;
}

TEST_CASE("reduced frames start at factor 2, within the limit", "[service][reduction]") {
  CHECK(ReductionPolicy(limitsOf(35.0, 8)).factor() == 2);
  CHECK(ReductionPolicy(limitsOf(35.0, 1)).factor() == 1);
  CHECK(ReductionPolicy(limitsOf(35.0, 50)).mostReduction() == ReductionPolicy::kMaxReduction);
}

TEST_CASE("a heavy scene settles at the sharpest factor that holds the budget",
          "[service][reduction]") {
  // 5 ms that no reduction saves, plus 400 ms of pixels at full size:
  // factor 2 takes 105 ms, 3 takes 49 ms, 4 takes 30 ms (the first within
  // 35 ms), 5 takes 21 ms.
  ReductionPolicy policy(limitsOf(35.0, 8));
  const auto factors = run(
      policy, [](int f) { return 5.0 + 400.0 / (f * f); }, 60);
  CHECK(factors.back() == 4);
  CHECK(std::count(factors.end() - 20, factors.end(), 4) == 20);
  CHECK(*std::max_element(factors.begin(), factors.end()) == 4);  // never blurrier than needed
}

TEST_CASE("a factor that does not pay off is given up", "[service][reduction]") {
  // Every frame costs 50 ms whatever its size (vertex-bound): reducing
  // further buys nothing, so the policy comes back to the least reduction
  // it tried above 1 rather than staying blurred at the largest.
  ReductionPolicy policy(limitsOf(35.0, 8));
  const auto factors = run(
      policy, [](int) { return 50.0; }, 60);
  CHECK(factors.back() == 2);
  CHECK(*std::max_element(factors.begin(), factors.end()) <= 8);
}

TEST_CASE("a light scene is shown at full resolution while interacting", "[service][reduction]") {
  ReductionPolicy policy(limitsOf(35.0, 8));
  const auto factors = run(
      policy, [](int f) { return 8.0 / (f * f) + 1.0; }, 10);
  CHECK(factors.front() == 2);
  CHECK(factors.back() == 1);
}

TEST_CASE("the factor never exceeds the configured limit", "[service][reduction]") {
  ReductionPolicy policy(limitsOf(1.0, 3));  // a budget no frame holds
  const auto factors = run(
      policy, [](int f) { return 1000.0 / (f * f); }, 30);
  CHECK(*std::max_element(factors.begin(), factors.end()) == 3);
  CHECK(factors.back() == 3);
}

TEST_CASE("the wait for a render turn counts toward the budget", "[service][reduction]") {
  // 5 ms that no reduction saves plus 100 ms of pixels at full size: alone,
  // factor 2 (30 ms) holds the 35 ms budget. Behind a 30 ms wait for its
  // turn every factor misses it, and larger ones still pay off.
  const auto renderMs = [](int f) { return 5.0 + 100.0 / (f * f); };
  ReductionPolicy alone(limitsOf(35.0, 8));
  ReductionPolicy waiting(limitsOf(35.0, 8));
  std::vector<int> aloneFactors;
  std::vector<int> waitingFactors;
  for (int k = 0; k < 40; ++k) {
    aloneFactors.push_back(alone.factor());
    alone.adapt(renderMs(alone.factor()), 0.0, false, false);
    waitingFactors.push_back(waiting.factor());
    waiting.adapt(renderMs(waiting.factor()), 30.0, false, false);
  }
  CHECK(std::count(aloneFactors.end() - 10, aloneFactors.end(), 2) == 10);
  CHECK(*std::min_element(waitingFactors.end() - 10, waitingFactors.end()) >= 4);
}

// Feeds frames (10 ms each, no wait), crowded or not, and returns coarse()
// before each.
std::vector<bool> details(ReductionPolicy& policy, const std::vector<bool>& crowded) {
  std::vector<bool> coarse;
  for (const bool q : crowded) {
    coarse.push_back(policy.coarse());
    policy.adapt(10.0, 0.0, policy.coarse(), q);
  }
  return coarse;
}

TEST_CASE("coarse stand-ins only while most frames meet other sessions' frames",
          "[service][reduction]") {
  ReductionPolicy policy(limitsOf(35.0, 8));
  SECTION("a session alone keeps every primitive") {
    const auto coarse = details(policy, std::vector<bool>(50, false));
    CHECK(std::count(coarse.begin(), coarse.end(), true) == 0);
  }
  SECTION("one crowded frame now and then does not switch") {
    std::vector<bool> crowded(50, false);
    for (std::size_t k = 0; k < crowded.size(); k += 5) {
      crowded[k] = true;
    }
    const auto coarse = details(policy, crowded);
    CHECK(std::count(coarse.begin(), coarse.end(), true) == 0);
  }
  SECTION("crowded frames switch to coarse, and frames alone back") {
    std::vector<bool> crowded(20, true);
    crowded.resize(40, false);
    const auto coarse = details(policy, crowded);
    CHECK_FALSE(coarse[0]);
    CHECK(coarse[3]);  // from the second crowded frame on
    CHECK(std::count(coarse.begin() + 3, coarse.begin() + 21, true) == 18);
    CHECK_FALSE(coarse.back());
    // Back to full some frames after the crowd left: four frames alone
    // leave a share of 0.7^4 = 0.24, five 0.17.
    CHECK(coarse[24]);
    CHECK_FALSE(coarse[26]);
  }
  SECTION("playback frames leave the detail as it is, and a new drag starts in full") {
    details(policy, std::vector<bool>(5, true));
    REQUIRE(policy.coarse());
    for (int k = 0; k < 20; ++k) {
      policy.adapt(10.0, 0.0, false, std::nullopt);
    }
    CHECK(policy.coarse());
    policy.newDrag();
    CHECK_FALSE(policy.coarse());
    const auto again = details(policy, {true, true, true});
    CHECK(again == std::vector<bool>{false, false, true});
  }
  SECTION("frames crowded every other time keep the detail steady") {
    std::vector<bool> crowded;
    for (int k = 0; k < 60; ++k) {
      crowded.push_back(k % 2 == 0);
    }
    const auto coarse = details(policy, crowded);
    const auto first = std::find(coarse.begin(), coarse.end(), true);
    REQUIRE(first != coarse.end());
    CHECK(std::all_of(first, coarse.end(), [](bool c) { return c; }));
  }
}

}  // namespace
}  // namespace crackvis::service
