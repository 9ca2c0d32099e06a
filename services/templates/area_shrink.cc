#include "services/templates/area_shrink.h"

#include <algorithm>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace rslam::templates {

namespace {

// sum[x] = sum over `rows` rows of row[x], for x in [x0, cols) (rows <= 257, so 16 bits hold
// it). Blocks of 16 columns stay in registers while the rows go by.
void SumRowsSse2(const uint8_t* first_row, std::size_t stride, int rows, int x0, int cols, uint16_t* sum) {
#if defined(__SSE2__)
  const __m128i zero = _mm_setzero_si128();
  for (; x0 + 16 <= cols; x0 += 16) {
    __m128i low = zero;
    __m128i high = zero;
    const uint8_t* p = first_row + x0;
    for (int y = 0; y < rows; ++y, p += stride) {
      const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
      low = _mm_add_epi16(low, _mm_unpacklo_epi8(v, zero));
      high = _mm_add_epi16(high, _mm_unpackhi_epi8(v, zero));
    }
    _mm_storeu_si128(reinterpret_cast<__m128i*>(sum + x0), low);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(sum + x0 + 8), high);
  }
#endif
  for (; x0 < cols; ++x0) {
    uint32_t s = 0;
    for (int y = 0; y < rows; ++y) s += first_row[static_cast<std::size_t>(y) * stride + x0];
    sum[x0] = static_cast<uint16_t>(s);
  }
}

#if defined(__x86_64__)
// The same with blocks of 32 columns (AVX2), the rest as above.
__attribute__((target("avx2"))) void SumRowsAvx2(const uint8_t* first_row, std::size_t stride, int rows, int x0,
                                                 int cols, uint16_t* sum) {
  for (; x0 + 32 <= cols; x0 += 32) {
    __m256i low = _mm256_setzero_si256();
    __m256i high = _mm256_setzero_si256();
    const uint8_t* p = first_row + x0;
    for (int y = 0; y < rows; ++y, p += stride) {
      low = _mm256_add_epi16(low, _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p))));
      high = _mm256_add_epi16(high, _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16))));
    }
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(sum + x0), low);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(sum + x0 + 16), high);
  }
  SumRowsSse2(first_row, stride, rows, x0, cols, sum);
}
#endif

// AVX2 when the CPU has it (decided once; the project is not built for a particular CPU).
void SumRows(const uint8_t* first_row, std::size_t stride, int rows, int cols, uint16_t* sum) {
#if defined(__x86_64__)
  static const bool avx2 = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  if (avx2) {
    SumRowsAvx2(first_row, stride, rows, 0, cols, sum);
    return;
  }
#endif
  SumRowsSse2(first_row, stride, rows, 0, cols, sum);
}

// out[4x + k] = float(sums[k * cols + x]) for k < 4: four 16-bit sum rows interleaved as floats.
void InterleaveToFloat(const uint16_t* sums, int cols, float* out) {
  const uint16_t* s0 = sums;
  const uint16_t* s1 = sums + cols;
  const uint16_t* s2 = sums + 2 * static_cast<std::size_t>(cols);
  const uint16_t* s3 = sums + 3 * static_cast<std::size_t>(cols);
  int x = 0;
#if defined(__SSE2__)
  const __m128i zero = _mm_setzero_si128();
  for (; x + 8 <= cols; x += 8) {
    const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(s0 + x));
    const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(s1 + x));
    const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(s2 + x));
    const __m128i d = _mm_loadu_si128(reinterpret_cast<const __m128i*>(s3 + x));
    const __m128i ab_low = _mm_unpacklo_epi16(a, b), ab_high = _mm_unpackhi_epi16(a, b);
    const __m128i cd_low = _mm_unpacklo_epi16(c, d), cd_high = _mm_unpackhi_epi16(c, d);
    const __m128i quads[4] = {_mm_unpacklo_epi32(ab_low, cd_low), _mm_unpackhi_epi32(ab_low, cd_low),
                              _mm_unpacklo_epi32(ab_high, cd_high), _mm_unpackhi_epi32(ab_high, cd_high)};
    for (int q = 0; q < 4; ++q) {  // each quad: columns x + 2q and x + 2q + 1, four lanes each
      _mm_storeu_ps(out + 4 * (x + 2 * q), _mm_cvtepi32_ps(_mm_unpacklo_epi16(quads[q], zero)));
      _mm_storeu_ps(out + 4 * (x + 2 * q + 1), _mm_cvtepi32_ps(_mm_unpackhi_epi16(quads[q], zero)));
    }
  }
#endif
  for (; x < cols; ++x) {
    out[4 * x] = static_cast<float>(s0[x]);
    out[4 * x + 1] = static_cast<float>(s1[x]);
    out[4 * x + 2] = static_cast<float>(s2[x]);
    out[4 * x + 3] = static_cast<float>(s3[x]);
  }
}

}  // namespace

AreaShrink::Axis AreaShrink::MakeAxis(int source, int target) {
  if (target < 1 || source < target) {
    throw std::invalid_argument("AreaShrink: cannot shrink " + std::to_string(source) + " pixels to " +
                                std::to_string(target));
  }
  Axis a;
  a.cell.resize(source);
  a.first_weight.resize(source);
  const double scale = static_cast<double>(source) / target;
  for (int j = 0; j < source; ++j) {
    const int cell = std::min(static_cast<int>(j / scale), target - 1);
    const double boundary = (cell + 1) * scale;
    a.cell[j] = cell;
    a.first_weight[j] = cell + 1 < target && j + 1 > boundary ? static_cast<float>(boundary - j) : 1.0f;
  }
  a.begin.assign(target, 0);
  a.end.assign(target, 0);
  for (int j = source - 1; j >= 0; --j) a.begin[a.cell[j]] = j;
  for (int c = 0; c < target; ++c) a.end[c] = c + 1 < target ? a.begin[c + 1] : source;
  return a;
}

AreaShrink::AreaShrink(int source_cols, int source_rows, int width, int height)
    : source_cols_(source_cols),
      source_rows_(source_rows),
      width_(width),
      height_(height),
      columns_(MakeAxis(source_cols, width)),
      rows_(MakeAxis(source_rows, height)) {}

void AreaShrink::Apply(const cv::Mat& source, cv::Mat& out) const {
  if (source.type() != CV_8UC1 || source.cols != source_cols_ || source.rows != source_rows_) {
    throw std::invalid_argument("AreaShrink: expected a " + std::to_string(source_cols_) + "x" +
                                std::to_string(source_rows_) + " CV_8UC1 image");
  }
  const int cols = source_cols_;
  // Bands (output rows) are kept four at a time, interleaved: lane k of column x of block j is
  // band 4j + k at column x, so the horizontal pass below handles four bands per instruction.
  constexpr int kLanes = 4;
  const int blocks = (height_ + kLanes - 1) / kLanes;
  // Every element is written before it is read: no zero-fill.
  const auto bands = std::make_unique_for_overwrite<float[]>(static_cast<std::size_t>(blocks) * cols * kLanes);
  // Vertical pass, per band of rows (one output row). The rows wholly inside the band are
  // summed as integers: exact, so the float band equals a row-by-row float sum bit for bit.
  // Then a straddling last row is added in float. A band that starts with the straddling row of
  // the band above (non-integer row ratio) is summed row by row in float from 0.
  const auto whole_rows_sums = std::make_unique_for_overwrite<uint16_t[]>(static_cast<std::size_t>(kLanes) * cols);
  auto add_row = [cols](float* band, const uint8_t* row, float weight) {
    for (int x = 0; x < cols; ++x) band[kLanes * x] += weight * static_cast<float>(row[x]);
  };
  for (int j = 0; j < blocks; ++j) {
    float* block = bands.get() + static_cast<std::size_t>(j) * cols * kLanes;
    bool row_by_row[kLanes] = {false, false, false, false};
    for (int k = 0; k < kLanes; ++k) {
      const int b = kLanes * j + k;
      uint16_t* sums = whole_rows_sums.get() + static_cast<std::size_t>(k) * cols;
      if (b >= height_) {  // padding lane: zeros, never stored
        std::fill(sums, sums + cols, uint16_t{0});
        continue;
      }
      const int begin = rows_.begin[b];
      const int end = rows_.end[b];
      const int whole_end = end > begin && rows_.first_weight[end - 1] < 1.0f ? end - 1 : end;
      row_by_row[k] = (begin > 0 && rows_.first_weight[begin - 1] < 1.0f) || whole_end - begin > 257;
      if (row_by_row[k]) {
        std::fill(sums, sums + cols, uint16_t{0});
      } else {  // 257 * 255 fits 16 bits
        SumRows(source.ptr<uint8_t>(begin), source.step[0], whole_end - begin, cols, sums);
      }
    }
    InterleaveToFloat(whole_rows_sums.get(), cols, block);
    for (int k = 0; k < kLanes && kLanes * j + k < height_; ++k) {
      const int b = kLanes * j + k;
      const int begin = rows_.begin[b];
      const int end = rows_.end[b];
      const int whole_end = end > begin && rows_.first_weight[end - 1] < 1.0f ? end - 1 : end;
      if (row_by_row[k]) {
        if (begin > 0 && rows_.first_weight[begin - 1] < 1.0f) {
          add_row(block + k, source.ptr<uint8_t>(begin - 1), 1.0f - rows_.first_weight[begin - 1]);
        }
        for (int y = begin; y < whole_end; ++y) add_row(block + k, source.ptr<uint8_t>(y), 1.0f);
      }
      if (whole_end < end) add_row(block + k, source.ptr<uint8_t>(whole_end), rows_.first_weight[whole_end]);
    }
  }
  // Horizontal pass, one output cell at a time in registers (summing into memory would chain
  // every addition through a store and a load), in the order of a left-to-right scatter; each
  // lane is one band, computed exactly as alone.
  out.create(height_, width_, CV_32F);
  const float norm = static_cast<float>(static_cast<double>(width_) * height_ /
                                        (static_cast<double>(source_cols_) * source_rows_ * 255.0));
  for (int j = 0; j < blocks; ++j) {
    const float* block = bands.get() + static_cast<std::size_t>(j) * cols * kLanes;
    const int count = std::min(kLanes, height_ - kLanes * j);
    for (int c = 0; c < width_; ++c) {
      const int begin = columns_.begin[c];
      alignas(16) float sum[kLanes];
#if defined(__SSE2__)
      __m128 acc = _mm_setzero_ps();
      if (begin > 0 && columns_.first_weight[begin - 1] < 1.0f) {
        const __m128 w = _mm_set1_ps(1.0f - columns_.first_weight[begin - 1]);
        acc = _mm_add_ps(acc, _mm_mul_ps(w, _mm_loadu_ps(block + kLanes * (begin - 1))));
      }
      for (int x = begin; x < columns_.end[c]; ++x) {
        acc = _mm_add_ps(acc, _mm_mul_ps(_mm_set1_ps(columns_.first_weight[x]), _mm_loadu_ps(block + kLanes * x)));
      }
      _mm_store_ps(sum, _mm_mul_ps(acc, _mm_set1_ps(norm)));
#else
      for (int k = 0; k < kLanes; ++k) sum[k] = 0.0f;
      if (begin > 0 && columns_.first_weight[begin - 1] < 1.0f) {
        const float w = 1.0f - columns_.first_weight[begin - 1];
        for (int k = 0; k < kLanes; ++k) sum[k] += w * block[kLanes * (begin - 1) + k];
      }
      for (int x = begin; x < columns_.end[c]; ++x) {
        for (int k = 0; k < kLanes; ++k) sum[k] += columns_.first_weight[x] * block[kLanes * x + k];
      }
      for (int k = 0; k < kLanes; ++k) sum[k] *= norm;
#endif
      for (int k = 0; k < count; ++k) out.ptr<float>(kLanes * j + k)[c] = sum[k];
    }
  }
}

}  // namespace rslam::templates
