#include "services/templates/window_sad.h"

#include <algorithm>
#include <cstdlib>

#if defined(__x86_64__) || defined(_M_X64)
#define RSLAM_WINDOW_SAD_X86 1
#include <immintrin.h>
#endif

namespace rslam::templates {

namespace {

uint64_t AbsoluteGap(uint32_t a, uint32_t b) { return a > b ? a - b : b - a; }

#if RSLAM_WINDOW_SAD_X86
// kLaneMask + 32 - n: n lanes of 0xff, then zeros (n in 0..32).
alignas(64) constexpr uint8_t kLaneMask[64] = {
    0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff,
    0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff,
    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,
    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0,    0};

// ---- SSE2 (part of x86-64: no run-time check needed) ----

inline __m128i Load16(const uint8_t* p) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)); }

inline uint64_t Sum64x2(__m128i v) {
  return static_cast<uint64_t>(_mm_cvtsi128_si64(_mm_add_epi64(v, _mm_unpackhi_epi64(v, v))));
}

uint64_t WindowSadSse2(const uint8_t* a, std::ptrdiff_t a_stride, const uint8_t* b, std::ptrdiff_t b_stride, int length,
                       int rows, uint64_t limit) {
  const int full = length / 16;
  const int tail = length % 16;
  const __m128i mask = Load16(kLaneMask + 32 - tail);
  uint64_t sum = 0;
  for (int y = 0; y < rows; ++y, a += a_stride, b += b_stride) {
    __m128i acc = _mm_setzero_si128();
    int k = 0;
    for (; k < full; ++k) acc = _mm_add_epi64(acc, _mm_sad_epu8(Load16(a + 16 * k), Load16(b + 16 * k)));
    if (tail) {
      acc = _mm_add_epi64(acc, _mm_sad_epu8(_mm_and_si128(mask, Load16(a + 16 * k)), _mm_and_si128(mask, Load16(b + 16 * k))));
    }
    sum += Sum64x2(acc);
    if (sum > limit) return sum;
  }
  return sum;
}

// kVectors 16-byte vectors per row (0: any number, counted at run time).
template <int kVectors>
ShiftedWindowsResult ShiftedWindowsSadSse2(const ShiftedWindows& s, const uint8_t* tmpl, uint32_t template_sum,
                                           uint64_t limit) {
  const int vectors = kVectors > 0 ? kVectors : (s.length + 15) / 16;
  // The template's lanes past `length` are zero; the view's are masked to zero.
  const __m128i mask = Load16(kLaneMask + 32 - (s.length - 16 * (vectors - 1)));
  ShiftedWindowsResult r;
  for (int w = 0; w < s.count; ++w) {
    const uint64_t cap = std::min(limit, r.best_sad);
    const uint64_t gap = AbsoluteGap(template_sum, s.view_sums[w]);
    uint64_t sad = gap;
    if (gap <= cap) {
      sad = 0;
      const uint8_t* t = tmpl;
      const uint8_t* v = s.view + s.view_offsets[w];
      for (int y = 0; y < s.rows; ++y, t += s.template_stride, v += s.view_stride) {
        __m128i acc = _mm_setzero_si128();
        for (int k = 0; k + 1 < vectors; ++k) acc = _mm_add_epi64(acc, _mm_sad_epu8(Load16(t + 16 * k), Load16(v + 16 * k)));
        const int last = 16 * (vectors - 1);
        acc = _mm_add_epi64(acc, _mm_sad_epu8(Load16(t + last), _mm_and_si128(mask, Load16(v + last))));
        sad += Sum64x2(acc);
        if (sad > cap) break;
      }
    }
    r.smallest_seen = std::min(r.smallest_seen, sad);
    if (sad <= cap && sad < r.best_sad) {
      r.best_sad = sad;
      r.best_window = w;
    }
  }
  return r;
}

// ---- AVX2: 32 lanes per instruction, used when the CPU has it ----

__attribute__((target("avx2"))) inline __m256i Load32(const uint8_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}

__attribute__((target("avx2"))) inline uint64_t Sum64x4(__m256i v) {
  return Sum64x2(_mm_add_epi64(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1)));
}

__attribute__((target("avx2"))) uint64_t WindowSadAvx2(const uint8_t* a, std::ptrdiff_t a_stride, const uint8_t* b,
                                                       std::ptrdiff_t b_stride, int length, int rows, uint64_t limit) {
  const int full = length / 32;
  const int tail = length % 32;
  const __m256i mask = Load32(kLaneMask + 32 - tail);
  uint64_t sum = 0;
  for (int y = 0; y < rows; ++y, a += a_stride, b += b_stride) {
    __m256i acc = _mm256_setzero_si256();
    int k = 0;
    for (; k < full; ++k) acc = _mm256_add_epi64(acc, _mm256_sad_epu8(Load32(a + 32 * k), Load32(b + 32 * k)));
    if (tail) {
      acc = _mm256_add_epi64(
          acc, _mm256_sad_epu8(_mm256_and_si256(mask, Load32(a + 32 * k)), _mm256_and_si256(mask, Load32(b + 32 * k))));
    }
    sum += Sum64x4(acc);
    if (sum > limit) return sum;
  }
  return sum;
}

template <int kVectors>
__attribute__((target("avx2"))) ShiftedWindowsResult ShiftedWindowsSadAvx2(const ShiftedWindows& s,
                                                                           const uint8_t* tmpl, uint32_t template_sum,
                                                                           uint64_t limit) {
  const int vectors = kVectors > 0 ? kVectors : (s.length + 31) / 32;
  const __m256i mask = Load32(kLaneMask + 32 - (s.length - 32 * (vectors - 1)));
  ShiftedWindowsResult r;
  for (int w = 0; w < s.count; ++w) {
    const uint64_t cap = std::min(limit, r.best_sad);
    const uint64_t gap = AbsoluteGap(template_sum, s.view_sums[w]);
    uint64_t sad = gap;
    if (gap <= cap) {
      sad = 0;
      const uint8_t* t = tmpl;
      const uint8_t* v = s.view + s.view_offsets[w];
      for (int y = 0; y < s.rows; ++y, t += s.template_stride, v += s.view_stride) {
        __m256i acc = _mm256_setzero_si256();
        for (int k = 0; k + 1 < vectors; ++k) {
          acc = _mm256_add_epi64(acc, _mm256_sad_epu8(Load32(t + 32 * k), Load32(v + 32 * k)));
        }
        const int last = 32 * (vectors - 1);
        acc = _mm256_add_epi64(acc, _mm256_sad_epu8(Load32(t + last), _mm256_and_si256(mask, Load32(v + last))));
        sad += Sum64x4(acc);
        if (sad > cap) break;
      }
    }
    r.smallest_seen = std::min(r.smallest_seen, sad);
    if (sad <= cap && sad < r.best_sad) {
      r.best_sad = sad;
      r.best_window = w;
    }
  }
  return r;
}

ShiftedWindowsResult ShiftedWindowsSadSse2Dispatch(const ShiftedWindows& s, const uint8_t* tmpl, uint32_t template_sum,
                                                   uint64_t limit) {
  switch ((s.length + 15) / 16) {
    case 1: return ShiftedWindowsSadSse2<1>(s, tmpl, template_sum, limit);
    case 2: return ShiftedWindowsSadSse2<2>(s, tmpl, template_sum, limit);
    case 3: return ShiftedWindowsSadSse2<3>(s, tmpl, template_sum, limit);
    case 4: return ShiftedWindowsSadSse2<4>(s, tmpl, template_sum, limit);
    default: return ShiftedWindowsSadSse2<0>(s, tmpl, template_sum, limit);
  }
}

__attribute__((target("avx2"))) ShiftedWindowsResult ShiftedWindowsSadAvx2Dispatch(const ShiftedWindows& s,
                                                                                   const uint8_t* tmpl,
                                                                                   uint32_t template_sum,
                                                                                   uint64_t limit) {
  switch ((s.length + 31) / 32) {
    case 1: return ShiftedWindowsSadAvx2<1>(s, tmpl, template_sum, limit);
    case 2: return ShiftedWindowsSadAvx2<2>(s, tmpl, template_sum, limit);
    default: return ShiftedWindowsSadAvx2<0>(s, tmpl, template_sum, limit);
  }
}

bool CpuHasAvx2() {
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return has;
}
#endif

}  // namespace

uint64_t WindowSadPortable(const uint8_t* a, std::ptrdiff_t a_stride, const uint8_t* b, std::ptrdiff_t b_stride,
                           int length, int rows, uint64_t limit) {
  uint64_t sum = 0;
  for (int y = 0; y < rows; ++y, a += a_stride, b += b_stride) {
    uint32_t row = 0;
    for (int x = 0; x < length; ++x) row += static_cast<uint32_t>(std::abs(int{a[x]} - int{b[x]}));
    sum += row;
    if (sum > limit) return sum;
  }
  return sum;
}

ShiftedWindowsResult ShiftedWindowsSadPortable(const ShiftedWindows& s, const uint8_t* tmpl, uint32_t template_sum,
                                               uint64_t limit) {
  ShiftedWindowsResult r;
  for (int w = 0; w < s.count; ++w) {
    const uint64_t cap = std::min(limit, r.best_sad);
    const uint64_t gap = AbsoluteGap(template_sum, s.view_sums[w]);
    const uint64_t sad = gap > cap ? gap
                                   : WindowSadPortable(tmpl, s.template_stride, s.view + s.view_offsets[w], s.view_stride,
                                                       s.length, s.rows, cap);
    r.smallest_seen = std::min(r.smallest_seen, sad);
    if (sad <= cap && sad < r.best_sad) {
      r.best_sad = sad;
      r.best_window = w;
    }
  }
  return r;
}

std::vector<WindowSadImplementation> AvailableWindowSadImplementations() {
  std::vector<WindowSadImplementation> all = {{"portable", &WindowSadPortable, &ShiftedWindowsSadPortable}};
#if RSLAM_WINDOW_SAD_X86
  all.push_back({"sse2", &WindowSadSse2, &ShiftedWindowsSadSse2Dispatch});
  if (CpuHasAvx2()) all.push_back({"avx2", &WindowSadAvx2, &ShiftedWindowsSadAvx2Dispatch});
#endif
  return all;
}

WindowSadFunction BestWindowSad() {
#if RSLAM_WINDOW_SAD_X86
  return CpuHasAvx2() ? &WindowSadAvx2 : &WindowSadSse2;
#else
  return &WindowSadPortable;
#endif
}

ShiftedWindowsFunction BestShiftedWindowsSad() {
#if RSLAM_WINDOW_SAD_X86
  return CpuHasAvx2() ? &ShiftedWindowsSadAvx2Dispatch : &ShiftedWindowsSadSse2Dispatch;
#else
  return &ShiftedWindowsSadPortable;
#endif
}

}  // namespace rslam::templates
