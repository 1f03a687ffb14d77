// The reduced-resolution rule of an interacting session (ReductionPolicy),
// fed modelled render times: the sharpest factor that holds the budget, a
// factor that does not pay off given up, the limits kept.
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
    policy.adaptReduction(renderMs(policy.factor()));
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

}  // namespace
}  // namespace crackvis::service
