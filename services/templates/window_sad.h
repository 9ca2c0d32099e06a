#pragma once
// Sums of absolute differences (SAD) of 8-bit windows: the inner loop of template matching
// (paper 000 eq. 8 and OpenRatSLAM's patch comparison, before the division by the pixel count).
// All sums are exact (integers).
//
// Speed: SSE2 (every x86-64) or AVX2 (chosen at run time when the CPU has it; the project is not
// compiled for a particular CPU); plain C++ elsewhere. Rows are read in whole vectors with the
// lanes past `length` masked, so every window must stay readable for RoundUp(length, 32) bytes
// from each row start (pad buffers with kWindowSadPadding bytes at the end).

#include <cstddef>
#include <cstdint>
#include <vector>

namespace rslam::templates {

inline constexpr int kWindowSadPadding = 64;

// SAD of two windows of `rows` rows x `length` columns. Stops after the first row at which the
// running sum exceeds `limit` and returns that partial sum: a result > limit means "at least
// this much"; a result <= limit is the whole window's SAD.
using WindowSadFunction = uint64_t (*)(const uint8_t* a, std::ptrdiff_t a_stride, const uint8_t* b,
                                       std::ptrdiff_t b_stride, int length, int rows, uint64_t limit);

// One template against windows of a view at several column offsets (the shifts tried), all of
// the same size. The template's rows hold its `length` compared columns followed by zeros up
// to template_stride (a multiple of 32).
struct ShiftedWindows {
  const uint8_t* view = nullptr;        // first row of the view
  std::ptrdiff_t view_stride = 0;
  const int* view_offsets = nullptr;    // per window: its first view column
  const uint32_t* view_sums = nullptr;  // per window: sum of the view's pixels in it
  int count = 0;                        // windows, in the order ties are decided (earlier wins)
  int length = 0;                       // columns compared
  int rows = 0;
  std::ptrdiff_t template_stride = 0;
};

struct ShiftedWindowsResult {
  int best_window = -1;            // the window with the smallest SAD <= limit (earliest on ties), or -1
  uint64_t best_sad = UINT64_MAX;  // its SAD
  // The smallest value met for any window: a complete SAD, a partial sum past the limit or
  // |template_sum - view_sums[w]| past the limit. Every window's SAD is at least this.
  uint64_t smallest_seen = UINT64_MAX;
};

// Windows in order; each is skipped when |template_sum - view_sums[w]| (a lower bound of its
// SAD) exceeds min(limit, best SAD so far), else its rows are summed until the sum does.
using ShiftedWindowsFunction = ShiftedWindowsResult (*)(const ShiftedWindows& windows, const uint8_t* tmpl,
                                                        uint32_t template_sum, uint64_t limit);

// The fastest implementations this CPU runs (decided once).
WindowSadFunction BestWindowSad();
ShiftedWindowsFunction BestShiftedWindowsSad();

// Every implementation this CPU runs, by name ("portable", "sse2", "avx2"), for tests.
struct WindowSadImplementation {
  const char* name;
  WindowSadFunction window_sad;
  ShiftedWindowsFunction shifted_windows_sad;
};
std::vector<WindowSadImplementation> AvailableWindowSadImplementations();

// Portable implementations (references for tests).
uint64_t WindowSadPortable(const uint8_t* a, std::ptrdiff_t a_stride, const uint8_t* b, std::ptrdiff_t b_stride,
                           int length, int rows, uint64_t limit);
ShiftedWindowsResult ShiftedWindowsSadPortable(const ShiftedWindows& windows, const uint8_t* tmpl,
                                               uint32_t template_sum, uint64_t limit);

}  // namespace rslam::templates
