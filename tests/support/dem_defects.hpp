// The malformed files of the foundation issue's validation list, each made by
// damaging a valid sample in one way, with the words the error must contain.
// Shared by the reader tests (tests/dem) and the CLI tests (tests/tools).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "support/sample_files.hpp"

namespace crackvis::testing {

struct DemDefect {
  std::string name;
  // Damages the valid sample at `path` (N particles, M bonds, 3 steps).
  std::function<void(const std::string& path, const SampleData& sample)> damage;
  std::vector<std::string> messageParts;  // every part must be in the message
};

// The defects for `sample`, whose sizes the expected messages quote.
std::vector<DemDefect> demDefects(const SampleData& sample);

}  // namespace crackvis::testing
