// "did you mean ...?": the edit distance and the nearest-name rule the CLI
// and crackvis-client use for misspelt subcommands and options.
#include <catch2/catch.hpp>

#include <crackvis/common/spelling.hpp>

namespace crackvis {
namespace {

TEST_CASE("The edit distance counts inserts, deletes, substitutions and swaps", "[common]") {
  CHECK(editDistance("", "") == 0);
  CHECK(editDistance("extract", "extract") == 0);
  CHECK(editDistance("extrat", "extract") == 1);  // a letter left out
  CHECK(editDistance("--stpe", "--step") == 1);   // two letters swapped
  CHECK(editDistance("heath", "health") == 1);
  CHECK(editDistance("export", "extract") == 4);
  CHECK(editDistance("abc", "") == 3);
  CHECK(editDistance("", "abc") == 3);
  CHECK(editDistance("kitten", "sitting") == 3);
}

TEST_CASE("The nearest name is offered only when it is close enough to be a typo", "[common]") {
  const std::vector<std::string> subcommands{"generate", "import",   "info", "extract",
                                             "export",   "snapshot", "sim",  "health"};
  CHECK(closestName("extrat", subcommands) == "extract");
  CHECK(closestName("exprot", subcommands) == "export");
  CHECK(closestName("helth", subcommands) == "health");
  CHECK(closestName("inf", subcommands) == "info");
  CHECK(closestName("render", subcommands).empty());
  CHECK(closestName("xyz", subcommands).empty());
  CHECK(closestName("extrat", {}).empty());
  const std::vector<std::string> options{"--step", "--steps", "--json", "--help", "-h"};
  CHECK(closestName("--stpe", options) == "--step");  // the first of equals: --steps is 2 away
  CHECK(closestName("--jsno", options) == "--json");
}

}  // namespace
}  // namespace crackvis
