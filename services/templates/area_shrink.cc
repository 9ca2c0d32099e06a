#include "services/templates/area_shrink.h"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace rslam::templates {

namespace {

// sum[x] = sum over `rows` rows of row[x], for x < cols (rows <= 257, so 16 bits hold it).
// Blocks of 16 columns stay in registers while the rows go by.
void SumRows(const uint8_t* first_row, std::size_t stride, int rows, int cols, uint16_t* sum) {
  int x0 = 0;
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
  // Vertical pass, per band of rows (one output row). The rows wholly inside the band are
  // summed as integers: exact, so the float band equals a row-by-row float sum bit for bit.
  // Then a straddling last row is added in float. A band that starts with the straddling row of
  // the band above (non-integer row ratio) is summed row by row in float.
  std::vector<float> bands(static_cast<std::size_t>(height_) * cols, 0.0f);
  std::vector<uint16_t> whole_rows_sum(cols);
  auto add_row = [cols](float* band, const uint8_t* row, float weight) {
    for (int x = 0; x < cols; ++x) band[x] += weight * static_cast<float>(row[x]);
  };
  for (int b = 0; b < height_; ++b) {
    float* band = bands.data() + static_cast<std::size_t>(b) * cols;
    const int begin = rows_.begin[b];
    const int end = rows_.end[b];
    const bool straddles_in = begin > 0 && rows_.first_weight[begin - 1] < 1.0f;
    const int whole_end = end > begin && rows_.first_weight[end - 1] < 1.0f ? end - 1 : end;
    if (!straddles_in && whole_end - begin <= 257) {  // 257 * 255 fits 16 bits
      SumRows(source.ptr<uint8_t>(begin), source.step[0], whole_end - begin, cols, whole_rows_sum.data());
      for (int x = 0; x < cols; ++x) band[x] = static_cast<float>(whole_rows_sum[x]);
    } else {
      if (straddles_in) add_row(band, source.ptr<uint8_t>(begin - 1), 1.0f - rows_.first_weight[begin - 1]);
      for (int y = begin; y < whole_end; ++y) add_row(band, source.ptr<uint8_t>(y), 1.0f);
    }
    if (whole_end < end) add_row(band, source.ptr<uint8_t>(whole_end), rows_.first_weight[whole_end]);
  }
  // Horizontal pass, one output cell at a time in registers (summing into memory would chain
  // every addition through a store and a load), in the order of a left-to-right scatter, for
  // four bands at once (four independent addition chains).
  out.create(height_, width_, CV_32F);
  const float norm = static_cast<float>(static_cast<double>(width_) * height_ /
                                        (static_cast<double>(source_cols_) * source_rows_ * 255.0));
  constexpr int kBandsAtOnce = 4;
  for (int b0 = 0; b0 < height_; b0 += kBandsAtOnce) {
    const int count = std::min(kBandsAtOnce, height_ - b0);
    const float* band[kBandsAtOnce];
    for (int k = 0; k < kBandsAtOnce; ++k) {
      band[k] = bands.data() + static_cast<std::size_t>(b0 + std::min(k, count - 1)) * cols;
    }
    for (int c = 0; c < width_; ++c) {
      const int begin = columns_.begin[c];
      float sum[kBandsAtOnce] = {0.0f, 0.0f, 0.0f, 0.0f};
      if (begin > 0 && columns_.first_weight[begin - 1] < 1.0f) {
        const float w = 1.0f - columns_.first_weight[begin - 1];
        for (int k = 0; k < kBandsAtOnce; ++k) sum[k] += w * band[k][begin - 1];
      }
      for (int x = begin; x < columns_.end[c]; ++x) {
        const float w = columns_.first_weight[x];
        for (int k = 0; k < kBandsAtOnce; ++k) sum[k] += w * band[k][x];
      }
      for (int k = 0; k < count; ++k) out.ptr<float>(b0 + k)[c] = sum[k] * norm;
    }
  }
}

}  // namespace rslam::templates
