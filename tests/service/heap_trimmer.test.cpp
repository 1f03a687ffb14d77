// The render server's deferred heap trim (HeapTrimmer): sessions that end
// close together are trimmed for once, after the server has been quiet; a
// stream of ends cannot put it off past `longest`; a trim still due runs
// when the server stops; the heap reserve is touched again after each trim,
// but not after the one at the stop.
#include <atomic>
#include <chrono>
#include <functional>
#include <thread>

#include <catch2/catch.hpp>

#include <crackvis/service/heap_trimmer.hpp>

namespace crackvis::service {
namespace {

using std::chrono::milliseconds;
using Clock = std::chrono::steady_clock;

bool waitFor(const std::function<bool()>& condition, milliseconds limit) {
  const auto until = Clock::now() + limit;
  while (!condition()) {
    if (Clock::now() > until) {
      return false;
    }
    std::this_thread::sleep_for(milliseconds(2));
  }
  return true;
}

TEST_CASE("ends close together are trimmed for once, after the quiet time", "[service][trim]") {
  std::atomic<int> trimmed{0};
  HeapTrimmer trimmer({milliseconds(300), milliseconds(60000)}, [&] { ++trimmed; });
  const auto start = Clock::now();
  trimmer.request();
  trimmer.request();
  trimmer.request();
  REQUIRE(waitFor([&] { return trimmer.trims() == 1; }, milliseconds(10000)));
  CHECK(Clock::now() - start >= milliseconds(300));
  CHECK(trimmed == 1);
  std::this_thread::sleep_for(milliseconds(400));
  CHECK(trimmed == 1);  // nothing more was asked for
  trimmer.request();
  REQUIRE(waitFor([&] { return trimmer.trims() == 2; }, milliseconds(10000)));
  CHECK(trimmed == 2);
}

TEST_CASE("a request within the quiet time puts the trim off", "[service][trim]") {
  std::atomic<int> trimmed{0};
  HeapTrimmer trimmer({milliseconds(3000), milliseconds(60000)}, [&] { ++trimmed; });
  trimmer.request();
  std::this_thread::sleep_for(milliseconds(500));
  const auto second = Clock::now();
  trimmer.request();
  REQUIRE(waitFor([&] { return trimmer.trims() == 1; }, milliseconds(20000)));
  // Three seconds after the second request, not after the first.
  CHECK(Clock::now() - second >= milliseconds(3000));
  CHECK(trimmed == 1);
}

TEST_CASE("ends that never stop are trimmed at least every `longest`", "[service][trim]") {
  std::atomic<int> trimmed{0};
  HeapTrimmer trimmer({milliseconds(1000), milliseconds(300)}, [&] { ++trimmed; });
  const auto start = Clock::now();
  // A request every 50 ms, far more often than the quiet time: the trim
  // comes all the same, at `longest`.
  while (trimmer.trims() == 0 && Clock::now() - start < milliseconds(10000)) {
    trimmer.request();
    std::this_thread::sleep_for(milliseconds(50));
  }
  CHECK(trimmer.trims() >= 1);
  CHECK(Clock::now() - start >= milliseconds(300));
  CHECK(Clock::now() - start < milliseconds(1000) + milliseconds(5000));
}

TEST_CASE("a trim still due runs when the trimmer stops", "[service][trim]") {
  std::atomic<int> trimmed{0};
  {
    HeapTrimmer trimmer({milliseconds(60000), milliseconds(60000)}, [&] { ++trimmed; });
    trimmer.request();
    CHECK(trimmed == 0);
  }
  CHECK(trimmed == 1);
  {
    HeapTrimmer idle({milliseconds(60000), milliseconds(60000)}, [&] { ++trimmed; });
  }
  CHECK(trimmed == 1);  // none asked for: none run
}

TEST_CASE("the reserve is touched again after each trim, not after the one at the stop",
          "[service][trim]") {
  std::atomic<int> trimmed{0};
  std::atomic<int> refilled{0};
  std::atomic<bool> refillAfterTrim{true};
  {
    HeapTrimmer trimmer(
        {milliseconds(1500), milliseconds(60000)}, [&] { ++trimmed; },
        [&] {
          refillAfterTrim = refillAfterTrim && refilled + 1 == trimmed;
          ++refilled;
        });
    trimmer.request();
    REQUIRE(waitFor([&] { return trimmer.trims() == 1; }, milliseconds(10000)));
    CHECK(refilled == 1);
    trimmer.request();
    REQUIRE(waitFor([&] { return trimmer.trims() == 2; }, milliseconds(10000)));
    CHECK(refilled == 2);
    trimmer.request();  // still due when the trimmer stops
  }
  CHECK(trimmed == 3);
  CHECK(refilled == 2);  // a server shutting down has no use for a reserve
  CHECK(refillAfterTrim);
}

}  // namespace
}  // namespace crackvis::service
