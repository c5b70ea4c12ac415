#pragma once
// splitmix64's output function (Steele, Lea and Flood 2014): a bijective
// mix of 64 bits, for seeds of independent random streams
// (synth/synthetic_rig.cpp) and for reproducible pseudo-random subsets
// (ident/refine_residual.cpp). No state: callers add the increment.
#include <cstdint>

namespace pneumaid::internal {

// splitmix64's increment (2^64 over the golden ratio).
inline constexpr std::uint64_t kSplitMix64Increment = 0x9E3779B97F4A7C15ULL;

// The mix of `z`, which callers step by kSplitMix64Increment.
inline constexpr std::uint64_t SplitMix64Mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

}  // namespace pneumaid::internal
