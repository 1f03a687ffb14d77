// Step selections on the command line: "A", "A:B" or "A:B:K", shared by
// every command that walks a series of steps (extract, bench, import).
#pragma once

#include <string>
#include <vector>

#include <crackvis/common/status.hpp>

namespace crackvis::dem {

// Parses "A", "A:B" or "A:B:K" (inclusive, stride K; negative A or B count
// from the end, -1 the last step) against a series of `stepCount` steps.
Result<std::vector<int>> parseStepRange(const std::string& text, int stepCount);

}  // namespace crackvis::dem
