#pragma once
// Counter-based draws: SplitMix64's output function, and the uniform and normal draws a seed
// and a text key fix (the same key gives the same draw in every run and on every machine).

#include <cmath>
#include <cstdint>
#include <string>

namespace depthbias::common {

inline std::uint64_t Mix64(std::uint64_t z) {  // SplitMix64's output function
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// The hash of (seed, key); i picks one of the draws that (seed, key) fixes.
inline std::uint64_t HashOf(std::uint64_t seed, const std::string& key, std::uint64_t i) {
  std::uint64_t h = Mix64(seed + 0x9E3779B97F4A7C15ULL);
  for (unsigned char ch : key) h = Mix64(h ^ ch);
  return Mix64(h + i);
}

// A uniform draw in (0, 1) fixed by (seed, key, i).
inline double UniformOf(std::uint64_t seed, const std::string& key, std::uint64_t i = 1) {
  return (static_cast<double>(HashOf(seed, key, i) >> 11) + 0.5) / 9007199254740992.0;
}

// A standard normal draw fixed by (seed, key): Box–Muller on the uniforms i = 1 and 2.
inline double NormalOf(std::uint64_t seed, const std::string& key) {
  return std::sqrt(-2 * std::log(UniformOf(seed, key, 1))) *
         std::cos(2 * M_PI * UniformOf(seed, key, 2));
}

}  // namespace depthbias::common
