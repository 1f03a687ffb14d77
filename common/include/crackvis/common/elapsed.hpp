// Milliseconds on the steady clock since a point, for the timings that
// sessions, sources and the step cache report.
#pragma once

#include <chrono>

namespace crackvis {

inline double millisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

}  // namespace crackvis
