#include <algorithm>
#include <charconv>

#include <fmt/format.h>

#include <crackvis/dem/step_range.hpp>

namespace crackvis::dem {

Result<std::vector<int>> parseStepRange(const std::string& text, int stepCount) {
  std::vector<long> parts;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(':', start), text.size());
    long value = 0;
    const char* first = text.data() + start;
    const char* last = text.data() + end;
    const auto [ptr, error] = std::from_chars(first, last, value);
    if (error != std::errc() || ptr != last || first == last) {
      return invalidArgument(
          fmt::format("step range '{}': expected A, A:B or A:B:K with integers", text));
    }
    parts.push_back(value);
    start = end + 1;
  }
  if (parts.size() > 3) {
    return invalidArgument(fmt::format("step range '{}': expected A, A:B or A:B:K", text));
  }
  if (stepCount <= 0) {
    return invalidArgument("the file has no steps");
  }
  auto resolve = [&](long value) { return value < 0 ? stepCount + value : value; };
  const long first = resolve(parts[0]);
  const long last = parts.size() >= 2 ? resolve(parts[1]) : first;
  const long stride = parts.size() == 3 ? parts[2] : 1;
  if (stride <= 0) {
    return invalidArgument(fmt::format("step range '{}': the stride must be positive", text));
  }
  if (first < 0 || first >= stepCount || last < 0 || last >= stepCount) {
    return invalidArgument(
        fmt::format("step range '{}' is outside the file's steps 0..{}", text, stepCount - 1));
  }
  if (last < first) {
    return invalidArgument(fmt::format("step range '{}' is empty (B < A)", text));
  }
  std::vector<int> steps;
  for (long s = first; s <= last; s += stride) {
    steps.push_back(static_cast<int>(s));
  }
  return steps;
}

}  // namespace crackvis::dem
