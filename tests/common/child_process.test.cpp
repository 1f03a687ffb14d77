// runInChild and capAddressSpace: the guard the CLI's readers put around
// libhdf5's first look at a file, and the cap on what that look may map.
#include <cstdlib>

#include <catch2/catch.hpp>
#include <sys/resource.h>

#include <crackvis/common/child_process.hpp>

namespace crackvis {
namespace {

constexpr std::uint64_t kMiB = std::uint64_t{1} << 20;

// Whether malloc of `bytes` succeeds in a child capped at `headroom`; the
// memory is touched, so a cap that did not hold would show as a fault.
std::string allocateInCappedChild(std::uint64_t headroom, std::size_t bytes) {
  auto outcome = runInChild(
      [&]() -> std::string {
        if (!capAddressSpace(headroom)) {
          return "cap failed";
        }
        auto* memory = static_cast<volatile char*>(std::malloc(bytes));
        if (memory == nullptr) {
          return "refused";
        }
        for (std::size_t i = 0; i < bytes; i += 4096) {
          memory[i] = 1;
        }
        std::free(const_cast<char*>(memory));
        return "allocated";
      },
      std::chrono::seconds(60));
  REQUIRE(outcome);
  REQUIRE(outcome->finished());
  return outcome->output;
}

TEST_CASE("A capped address space refuses an allocation past its headroom", "[common]") {
  // 8 GiB is what a corrupt size in a file asks of libhdf5; uncapped, this
  // machine's malloc hands it out (overcommit) and the fill takes the host.
  CHECK(allocateInCappedChild(256 * kMiB, std::size_t{8} << 30) == "refused");
  CHECK(allocateInCappedChild(256 * kMiB, 64 * kMiB) == "allocated");
}

TEST_CASE("A cap never raises a lower limit already set", "[common]") {
  auto outcome = runInChild(
      [] {
        if (!capAddressSpace(std::uint64_t{1} << 40)) {
          return std::string("cap failed");
        }
        rlimit first{};
        ::getrlimit(RLIMIT_AS, &first);
        if (!capAddressSpace(std::uint64_t{2} << 40)) {
          return std::string("cap failed");
        }
        rlimit second{};
        ::getrlimit(RLIMIT_AS, &second);
        return std::string(first.rlim_cur != RLIM_INFINITY && second.rlim_cur == first.rlim_cur &&
                                   second.rlim_max == first.rlim_max
                               ? "kept"
                               : "changed");
      },
      std::chrono::seconds(60));
  REQUIRE(outcome);
  REQUIRE(outcome->finished());
  CHECK(outcome->output == "kept");
}

}  // namespace
}  // namespace crackvis
