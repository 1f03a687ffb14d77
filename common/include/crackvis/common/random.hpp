// A seeded random generator with a fixed, documented output sequence
// (splitmix64; Steele, Lea and Flood 2014): a seed means the same numbers on
// every compiler and standard library, which the std:: distributions do not
// promise. Used wherever a seed must reproduce a file bit for bit (lattice
// jitter, bond strengths).
#pragma once

#include <cstdint>

namespace crackvis {

class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : m_state(seed) {}

  std::uint64_t next() {
    std::uint64_t z = (m_state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  // Uniform in [-1, 1).
  double symmetric() { return static_cast<double>(next() >> 11) * 0x1.0p-52 - 1.0; }
  // Uniform in (0, 1]: never 0, so -ln U is finite.
  double uniformOpenClosed() { return static_cast<double>((next() >> 11) + 1) * 0x1.0p-53; }

 private:
  std::uint64_t m_state;
};

}  // namespace crackvis
