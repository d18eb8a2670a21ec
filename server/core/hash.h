// Stateless hashing for procedural volumes: every value a pure function of its inputs, so the
// output is the same whatever the thread count or evaluation order.
#pragma once

#include <cstdint>

namespace peakcast {

inline uint64_t splitmix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Uniform in [0, 1) from (seed, a, b, c, salt).
inline double hash01(uint64_t seed, int64_t a, int64_t b, int64_t c, uint64_t salt = 0) {
  uint64_t h = splitmix(seed ^ salt);
  h = splitmix(h ^ uint64_t(a));
  h = splitmix(h ^ uint64_t(b));
  h = splitmix(h ^ uint64_t(c));
  return double(h >> 11) * (1.0 / 9007199254740992.0);
}

}  // namespace peakcast
