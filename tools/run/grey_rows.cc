#include "tools/run/grey_rows.h"

#include <opencv2/imgproc.hpp>

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace rslam::run {

namespace {

#if defined(__x86_64__)
// OpenCV 4's BGR2GRAY for 8 bits: grey = (3735 B + 19235 G + 9798 R + 2^14) >> 15 (weights
// 0.114, 0.587, 0.299 in 15-bit fixed point). Exact integer arithmetic, so any order of the
// sums gives the same byte; whether this OpenCV uses these weights is checked at run time.
constexpr int kBlueWeight = 3735;
constexpr int kGreenWeight = 19235;
constexpr int kRedWeight = 9798;
constexpr int kShift = 15;

// n BGR pixels to grey, 16 per step: the 48 bytes are deinterleaved into B, G and R as 16-bit
// lanes by byte shuffles (lane 0 takes pixels 0-7, lane 1 pixels 8-15), then B*wb + G*wg and
// R*wr + half come from two multiply-adds of (B, G) and (R, half) pairs.
__attribute__((target("avx2"))) void BgrToGreyAvx2(const uint8_t* src, uint8_t* dst, int n) {
  // Within 8 pixels (24 bytes): bytes 0-15 hold B at 0,3,..,15, G at 1,4,..,13, R at 2,5,..,14;
  // bytes 16-23 hold the rest. Each shuffle puts a channel's bytes in the low half of 16-bit lanes.
  const __m256i lo_b = _mm256_broadcastsi128_si256(_mm_setr_epi8(0, -1, 3, -1, 6, -1, 9, -1, 12, -1, 15, -1, -1, -1, -1, -1));
  const __m256i hi_b = _mm256_broadcastsi128_si256(_mm_setr_epi8(-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, 2, -1, 5, -1));
  const __m256i lo_g = _mm256_broadcastsi128_si256(_mm_setr_epi8(1, -1, 4, -1, 7, -1, 10, -1, 13, -1, -1, -1, -1, -1, -1, -1));
  const __m256i hi_g = _mm256_broadcastsi128_si256(_mm_setr_epi8(-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, 0, -1, 3, -1, 6, -1));
  const __m256i lo_r = _mm256_broadcastsi128_si256(_mm_setr_epi8(2, -1, 5, -1, 8, -1, 11, -1, 14, -1, -1, -1, -1, -1, -1, -1));
  const __m256i hi_r = _mm256_broadcastsi128_si256(_mm_setr_epi8(-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, 1, -1, 4, -1, 7, -1));
  const __m256i weights_bg = _mm256_set1_epi32((kGreenWeight << 16) | kBlueWeight);
  const __m256i weights_r_one = _mm256_set1_epi32((1 << 16) | kRedWeight);
  const __m256i half = _mm256_set1_epi16(1 << (kShift - 1));
  int i = 0;
  for (; i + 16 <= n; i += 16) {
    const uint8_t* p = src + 3 * i;
    const __m256i lo = _mm256_loadu2_m128i(reinterpret_cast<const __m128i*>(p + 24), reinterpret_cast<const __m128i*>(p));
    const __m256i hi = _mm256_inserti128_si256(
        _mm256_castsi128_si256(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p + 16))),
        _mm_loadl_epi64(reinterpret_cast<const __m128i*>(p + 40)), 1);
    const __m256i b = _mm256_or_si256(_mm256_shuffle_epi8(lo, lo_b), _mm256_shuffle_epi8(hi, hi_b));
    const __m256i g = _mm256_or_si256(_mm256_shuffle_epi8(lo, lo_g), _mm256_shuffle_epi8(hi, hi_g));
    const __m256i r = _mm256_or_si256(_mm256_shuffle_epi8(lo, lo_r), _mm256_shuffle_epi8(hi, hi_r));
    const __m256i sum_lo = _mm256_add_epi32(_mm256_madd_epi16(_mm256_unpacklo_epi16(b, g), weights_bg),
                                            _mm256_madd_epi16(_mm256_unpacklo_epi16(r, half), weights_r_one));
    const __m256i sum_hi = _mm256_add_epi32(_mm256_madd_epi16(_mm256_unpackhi_epi16(b, g), weights_bg),
                                            _mm256_madd_epi16(_mm256_unpackhi_epi16(r, half), weights_r_one));
    const __m256i words = _mm256_packs_epi32(_mm256_srli_epi32(sum_lo, kShift), _mm256_srli_epi32(sum_hi, kShift));
    const __m256i bytes = _mm256_packus_epi16(words, words);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(dst + i), _mm256_castsi256_si128(bytes));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(dst + i + 8), _mm256_extracti128_si256(bytes, 1));
  }
  for (; i < n; ++i) {
    const uint8_t* p = src + 3 * static_cast<std::size_t>(i);
    const int sum = p[0] * kBlueWeight + p[1] * kGreenWeight + p[2] * kRedWeight;
    dst[i] = static_cast<uint8_t>((sum + (1 << (kShift - 1))) >> kShift);
  }
}

// Every colour through the kernel and through cv::cvtColor, one red value (256 x 256 blue and
// green) at a time; rows of 256 pixels also exercise the 16-pixel steps only (no tail), so the
// tail is checked separately on odd widths.
bool KernelMatchesOpenCv() {
  cv::Mat colours(256, 256, CV_8UC3);
  cv::Mat expected;
  cv::Mat actual(256, 256, CV_8UC1);
  for (int red = 0; red < 256; ++red) {
    for (int g = 0; g < 256; ++g) {
      uint8_t* row = colours.ptr<uint8_t>(g);
      for (int b = 0; b < 256; ++b) {
        row[3 * b] = static_cast<uint8_t>(b);
        row[3 * b + 1] = static_cast<uint8_t>(g);
        row[3 * b + 2] = static_cast<uint8_t>(red);
      }
    }
    cv::cvtColor(colours, expected, cv::COLOR_BGR2GRAY);
    for (int g = 0; g < 256; ++g) BgrToGreyAvx2(colours.ptr<uint8_t>(g), actual.ptr<uint8_t>(g), 256);
    if (cv::countNonZero(expected != actual) != 0) return false;
    // Tails: widths 1..31 starting at odd offsets.
    for (int width = 1; width < 32; ++width) {
      const cv::Mat part = colours(cv::Rect(red % 200 + 1, width, width, 1));
      cv::Mat part_expected;
      cv::cvtColor(part, part_expected, cv::COLOR_BGR2GRAY);
      uint8_t out[32];
      BgrToGreyAvx2(part.ptr<uint8_t>(0), out, width);
      for (int x = 0; x < width; ++x) {
        if (out[x] != part_expected.at<uint8_t>(0, x)) return false;
      }
    }
  }
  return true;
}
#endif

bool UseFastKernel() {
#if defined(__x86_64__)
  static const bool use = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && KernelMatchesOpenCv();
  }();
  return use;
#else
  return false;
#endif
}

}  // namespace

bool FastBgrToGreyInUse() { return UseFastKernel(); }

cv::Mat ToGreyRows(const cv::Mat& image, int row_begin, int row_end, cv::Mat& buffer) {
  if (image.empty()) throw std::invalid_argument("empty image");
  if (image.depth() != CV_8U) throw std::invalid_argument("image is not 8 bits per channel");
  const int channels = image.channels();
  if (channels != 1 && channels != 3 && channels != 4) {
    throw std::invalid_argument("image has " + std::to_string(channels) + " channels (expected 1, 3 or 4)");
  }
  if (row_begin < 0 || row_end > image.rows || row_begin >= row_end) {
    throw std::invalid_argument("rows [" + std::to_string(row_begin) + ", " + std::to_string(row_end) +
                                ") are not within the " + std::to_string(image.rows) + " rows of the image");
  }
  if (channels == 1) return image;
  buffer.create(image.size(), CV_8UC1);
  const cv::Range rows(row_begin, row_end);
#if defined(__x86_64__)
  if (channels == 3 && UseFastKernel()) {
    for (int y = row_begin; y < row_end; ++y) BgrToGreyAvx2(image.ptr<uint8_t>(y), buffer.ptr<uint8_t>(y), image.cols);
    return buffer;
  }
#endif
  cv::Mat out = buffer.rowRange(rows);
  cv::cvtColor(image.rowRange(rows), out, channels == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
  return buffer;
}

}  // namespace rslam::run
