#pragma once
// The k-th smallest of a vector of doubles: the value std::nth_element leaves at v[k], found
// faster for the non-negative values the metrics take medians of (residuals, standard
// deviations). Header-only, like the rest of common.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace depthbias::common {

// The k-th smallest (0-based, k < v.size()) of v; v may be reordered. When every value is a
// non-negative number or +inf (no sign bit, so no −0; no NaN), their bit patterns order as the
// values do, and a radix selection on them (11 bits at a time from the top, the last 9)
// narrows the candidates in a few passes without a comparison that branches; otherwise, and on
// the last few candidates, std::nth_element. The same value std::nth_element gives either way.
inline double NthSmallest(std::vector<double>& v, std::size_t k) {
  const std::size_t n = v.size();
  constexpr std::size_t kSmall = 256;  // fewer candidates: std::nth_element
  if (n <= kSmall) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
  }
  std::vector<std::uint64_t> keys(n);
  bool plain = true;  // every value >= +0 and not NaN
  for (std::size_t i = 0; i < n; ++i) {
    std::memcpy(&keys[i], &v[i], sizeof(double));
    plain &= !std::signbit(v[i]) & !std::isnan(v[i]);
  }
  if (!plain) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
  }
  constexpr int kBits = 11;
  std::array<std::uint32_t, 1u << kBits> count;
  std::size_t m = n;  // candidates keys[0, m), rank k among them
  for (int shift = 64 - kBits; shift > -kBits && m > kSmall; shift -= kBits) {
    const int s = std::max(shift, 0);
    const std::uint64_t mask = (std::uint64_t{1} << (shift + kBits - s)) - 1;
    count.fill(0);
    for (std::size_t i = 0; i < m; ++i) ++count[(keys[i] >> s) & mask];
    std::uint64_t digit = 0;
    std::size_t below = 0;
    while (below + count[digit] <= k) below += count[digit++];
    if (count[digit] == m) continue;  // every candidate shares this digit
    std::size_t kept = 0;
    for (std::size_t i = 0; i < m; ++i) {
      const std::uint64_t key = keys[i];
      keys[kept] = key;
      kept += ((key >> s) & mask) == digit;
    }
    m = kept;
    k -= below;
  }
  std::nth_element(keys.begin(), keys.begin() + static_cast<std::ptrdiff_t>(k),
                   keys.begin() + static_cast<std::ptrdiff_t>(m));
  double out;
  std::memcpy(&out, &keys[k], sizeof(double));
  return out;
}

}  // namespace depthbias::common
