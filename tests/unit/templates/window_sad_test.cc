// Pins the SAD kernels behind template matching: every implementation this CPU runs (portable,
// SSE2, AVX2) gives exactly the sums of the plain definition, including where it stops.
#include "services/templates/window_sad.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <random>
#include <vector>

namespace rslam::templates {
namespace {

// The definition: rows summed in order, stopping after the first row that passes the limit.
uint64_t ReferenceSad(const uint8_t* a, std::ptrdiff_t a_stride, const uint8_t* b, std::ptrdiff_t b_stride, int length,
                      int rows, uint64_t limit) {
  uint64_t sum = 0;
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < length; ++x) sum += std::abs(int{a[y * a_stride + x]} - int{b[y * b_stride + x]});
    if (sum > limit) break;
  }
  return sum;
}

std::vector<uint8_t> RandomBytes(std::size_t n, std::mt19937& rng) {
  std::vector<uint8_t> v(n);
  for (auto& x : v) x = static_cast<uint8_t>(rng() & 0xff);
  return v;
}

TEST(WindowSadTest, EveryImplementationGivesTheExactSumAndStopsWhereTheDefinitionDoes) {
  std::mt19937 rng(7);
  const auto implementations = AvailableWindowSadImplementations();
  ASSERT_GE(implementations.size(), 1u);
  for (int length = 1; length <= 100; ++length) {
    for (int rows : {1, 3, 10}) {
      const int stride = length + 3;
      const std::vector<uint8_t> a = RandomBytes(static_cast<std::size_t>(stride) * rows + kWindowSadPadding, rng);
      const std::vector<uint8_t> b = RandomBytes(static_cast<std::size_t>(stride) * rows + kWindowSadPadding, rng);
      const uint64_t full = ReferenceSad(a.data(), stride, b.data(), stride, length, rows, UINT64_MAX);
      for (uint64_t limit : {uint64_t{0}, full / 3, full - 1, full, UINT64_MAX}) {
        const uint64_t expected = ReferenceSad(a.data(), stride, b.data(), stride, length, rows, limit);
        for (const auto& impl : implementations) {
          EXPECT_EQ(impl.window_sad(a.data(), stride, b.data(), stride, length, rows, limit), expected)
              << impl.name << " length " << length << " rows " << rows << " limit " << limit;
        }
      }
    }
  }
}

// The definition of a shifted-window scan, window by window.
ShiftedWindowsResult ReferenceScan(const ShiftedWindows& s, const uint8_t* tmpl, uint32_t template_sum, uint64_t limit) {
  ShiftedWindowsResult r;
  for (int w = 0; w < s.count; ++w) {
    const uint64_t cap = std::min(limit, r.best_sad);
    const uint64_t gap = template_sum > s.view_sums[w] ? template_sum - s.view_sums[w] : s.view_sums[w] - template_sum;
    const uint64_t sad =
        gap > cap ? gap
                  : ReferenceSad(tmpl, s.template_stride, s.view + s.view_offsets[w], s.view_stride, s.length, s.rows, cap);
    r.smallest_seen = std::min(r.smallest_seen, sad);
    if (sad <= cap && sad < r.best_sad) {
      r.best_sad = sad;
      r.best_window = w;
    }
  }
  return r;
}

// Windows at shifts 0..count-1 of a view (row stride view_stride), with their pixel sums.
struct ConsecutiveWindows {
  std::vector<int> offsets;
  std::vector<uint32_t> sums;
  ShiftedWindows set;
  ConsecutiveWindows(const std::vector<uint8_t>& view, int view_stride, int count, int length, int rows,
                     int template_stride) {
    for (int s = 0; s < count; ++s) {
      offsets.push_back(s);
      uint32_t sum = 0;
      for (int y = 0; y < rows; ++y) {
        for (int x = 0; x < length; ++x) sum += view[y * view_stride + x + s];
      }
      sums.push_back(sum);
    }
    set.view = view.data();
    set.view_stride = view_stride;
    set.view_offsets = offsets.data();
    set.view_sums = sums.data();
    set.count = count;
    set.length = length;
    set.rows = rows;
    set.template_stride = template_stride;
  }
  ConsecutiveWindows(const ConsecutiveWindows&) = delete;
};

TEST(WindowSadTest, ShiftedWindowScansAgreeWithTheDefinitionInEveryImplementation) {
  std::mt19937 rng(11);
  const auto implementations = AvailableWindowSadImplementations();
  for (int length : {1, 15, 16, 17, 31, 32, 33, 50, 60, 64, 65, 100}) {
    const int rows = 1 + length % 7;
    const int template_stride = (length + 31) / 32 * 32;
    const int shift = 5;
    const int view_stride = length + 2 * shift;
    // The view: a random row pattern; the template: the view's centre window plus a little noise
    // (so a few shifts come close), zero past `length`.
    const std::vector<uint8_t> view = RandomBytes(static_cast<std::size_t>(view_stride) * rows + kWindowSadPadding, rng);
    std::vector<uint8_t> tmpl(static_cast<std::size_t>(template_stride) * rows + kWindowSadPadding, 0);
    uint32_t template_sum = 0;
    for (int y = 0; y < rows; ++y) {
      for (int x = 0; x < length; ++x) {
        const int v = view[y * view_stride + x + shift] + static_cast<int>(rng() % 5) - 2;
        tmpl[y * template_stride + x] = static_cast<uint8_t>(std::clamp(v, 0, 255));
        template_sum += tmpl[y * template_stride + x];
      }
    }
    const ConsecutiveWindows windows(view, view_stride, 2 * shift + 1, length, rows, template_stride);
    const ShiftedWindows& set = windows.set;
    const ShiftedWindowsResult all = ReferenceScan(set, tmpl.data(), template_sum, UINT64_MAX);
    ASSERT_EQ(all.best_window, shift);
    for (uint64_t limit : {uint64_t{0}, all.best_sad, all.best_sad + 1, 50 * static_cast<uint64_t>(length), UINT64_MAX}) {
      const ShiftedWindowsResult expected = ReferenceScan(set, tmpl.data(), template_sum, limit);
      for (const auto& impl : implementations) {
        const ShiftedWindowsResult got = impl.shifted_windows_sad(set, tmpl.data(), template_sum, limit);
        EXPECT_EQ(got.best_window, expected.best_window) << impl.name << " length " << length << " limit " << limit;
        EXPECT_EQ(got.best_sad, expected.best_sad) << impl.name << " length " << length << " limit " << limit;
        EXPECT_EQ(got.smallest_seen, expected.smallest_seen) << impl.name << " length " << length << " limit " << limit;
      }
    }
  }
}

// Panoramic matching tries every wrapped shift: many windows, the best one late.
TEST(WindowSadTest, ScansOfManyWindowsAgreeWithTheDefinitionInEveryImplementation) {
  std::mt19937 rng(5);
  const auto implementations = AvailableWindowSadImplementations();
  const int length = 60, rows = 10, windows = 150;
  const int template_stride = 64;
  const int view_stride = length + windows;
  const std::vector<uint8_t> view = RandomBytes(static_cast<std::size_t>(view_stride) * rows + kWindowSadPadding, rng);
  std::vector<uint8_t> tmpl(static_cast<std::size_t>(template_stride) * rows + kWindowSadPadding, 0);
  uint32_t template_sum = 0;
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < length; ++x) {
      // Close to the view at shift 100, far into the scan.
      const int v = view[y * view_stride + x + 100] + static_cast<int>(rng() % 5) - 2;
      tmpl[y * template_stride + x] = static_cast<uint8_t>(std::clamp(v, 0, 255));
      template_sum += tmpl[y * template_stride + x];
    }
  }
  const ConsecutiveWindows scan(view, view_stride, windows, length, rows, template_stride);
  const ShiftedWindows& set = scan.set;
  const ShiftedWindowsResult all = ReferenceScan(set, tmpl.data(), template_sum, UINT64_MAX);
  ASSERT_EQ(all.best_window, 100);
  ASSERT_GT(all.best_sad, 0u);
  for (uint64_t limit : {uint64_t{0}, all.best_sad - 1, all.best_sad, uint64_t{2000}, uint64_t{40000}, UINT64_MAX}) {
    const ShiftedWindowsResult expected = ReferenceScan(set, tmpl.data(), template_sum, limit);
    for (const auto& impl : implementations) {
      const ShiftedWindowsResult got = impl.shifted_windows_sad(set, tmpl.data(), template_sum, limit);
      EXPECT_EQ(got.best_window, expected.best_window) << impl.name << " limit " << limit;
      EXPECT_EQ(got.best_sad, expected.best_sad) << impl.name << " limit " << limit;
      EXPECT_EQ(got.smallest_seen, expected.smallest_seen) << impl.name << " limit " << limit;
    }
  }
}

TEST(WindowSadTest, EqualSadsGoToTheEarlierWindow) {
  // Two identical windows: the first one wins in every implementation.
  std::vector<uint8_t> view(64 + kWindowSadPadding, 0);
  std::vector<uint8_t> tmpl(32 + kWindowSadPadding, 0);
  for (int x = 0; x < 8; ++x) view[x] = view[8 + x] = tmpl[x] = static_cast<uint8_t>(10 * x + 1);
  const int offsets[] = {8, 0};
  const uint32_t sums[] = {0, 0};
  ShiftedWindows set;
  set.view = view.data();
  set.view_stride = 64;
  set.view_offsets = offsets;
  set.view_sums = sums;
  set.count = 2;
  set.length = 8;
  set.rows = 1;
  set.template_stride = 32;
  for (const auto& impl : AvailableWindowSadImplementations()) {
    const ShiftedWindowsResult r = impl.shifted_windows_sad(set, tmpl.data(), 0, UINT64_MAX);
    EXPECT_EQ(r.best_window, 0) << impl.name;
    EXPECT_EQ(r.best_sad, 0u) << impl.name;
  }
}

}  // namespace
}  // namespace rslam::templates
