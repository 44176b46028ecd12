// Visiting the returns of one label, 16 labels at a time (SSE2) where it can: the ground
// stages after labelPoints() each test only the returns of one label.
#pragma once

#include <cstddef>
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ladar_perception {
namespace vertical_scan {

// Calls f(i) for every i < n with labels[i] == label, in increasing i.
template <typename F>
inline void forEachLabelled(const uint8_t* labels, std::size_t n, uint8_t label, F&& f) {
  std::size_t i = 0;
#if defined(__SSE2__)
  const __m128i v_label = _mm_set1_epi8(static_cast<char>(label));
  for (; i + 16 <= n; i += 16) {
    const __m128i l16 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(labels + i));
    for (unsigned m = static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(l16, v_label))); m;
         m &= m - 1) {
      f(i + static_cast<std::size_t>(__builtin_ctz(m)));
    }
  }
#endif
  for (; i < n; ++i) {
    if (labels[i] == label) f(i);
  }
}

}  // namespace vertical_scan
}  // namespace ladar_perception
