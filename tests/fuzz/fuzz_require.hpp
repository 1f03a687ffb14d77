// The fuzz targets' own checks. A failed check names the target and what
// broke, then traps, so that libFuzzer keeps the input as a crash. Each
// target defines kFuzzTargetName ("pipeline fuzzer").
#pragma once

#include <cstdio>

extern const char* const kFuzzTargetName;

inline void require(bool condition, const char* what) {
  if (!condition) {
    std::fprintf(stderr, "%s: %s\n", kFuzzTargetName, what);
    __builtin_trap();
  }
}
