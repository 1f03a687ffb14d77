// "did you mean ...?" for command lines: the known name closest to a
// misspelt one, by edit distance.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace crackvis {

// Edits (insert, delete, substitute, swap two neighbours) from `a` to `b`.
std::size_t editDistance(std::string_view a, std::string_view b);

// The candidate closest to `word`, if it is close enough to be a typo (at
// most one edit in three characters, at least one; the first of equals);
// empty otherwise.
std::string closestName(std::string_view word, const std::vector<std::string>& candidates);

}  // namespace crackvis
