#pragma once
// The local view: a library of visual templates that recognises familiar views and learns new
// ones. Three modes (TemplateConfig::mode):
//
//  column    Column-intensity arrays compared over shifts s (Milford & Wyeth 2008, paper 000
//            eq. 8): f(k) = mean |I_{n+max(s,0)} - I^k_{n-min(s,0)}| over the w - |s| overlap,
//            minimised over |s| <= shift_match; new template when min f(k) > match_threshold.
//  patch     OpenRatSLAM's 2-D templates: the centre window (shift_match columns in from each
//            side) of the view against the template shifted by |s| <= shift_match (or, with
//            `panoramic`, every wrapped shift of the whole template); difference = mean
//            absolute difference; new template above match_threshold.
//  histogram Prasser et al. 2004 (paper 001): Jeffrey divergence (eq. 1) of the view's
//            normalised grey histogram against every stored one; templates within
//            histogram_divergence_threshold are candidates, refined by the mean absolute
//            difference over all rotation_image_width rotations of the small panorama with the
//            dead-zone columns of both images masked and normalised by the pixels compared.
//            No candidate (or none within rotation_sad_threshold) -> new template.
//
// Intensities are in [0, 1]. `difference` and Differences() are in the mode's unit: mean
// absolute difference (column, patch) or Jeffrey divergence (histogram). With an empty library
// MatchOrLearn reports difference = +infinity.
//
// Relative angle: positive when the current view is the template's view with the scene moved
// towards larger x, i.e. the robot has turned counter-clockwise (left) since the template was
// learnt, assuming x increases clockwise around the robot (a forward camera; a panorama
// unwrapped the same way). Non-panoramic: shift * crop_fov_deg / template_x_size; panoramic and
// histogram: shift * 360 deg / width, wrapped to (-pi, pi]. In histogram mode the shift is the
// rotation index r (0..35) of paper 001, recoverable as round(angle / 10 deg) mod 36.
//
// Speed: templates live in one contiguous 8-bit buffer, each row holding just the columns every
// shift compares (patch, panoramic), zero-padded to whole SIMD vectors; sums of absolute
// differences use SSE2 or, when the CPU has it, AVX2 (window_sad.h). A template is abandoned as
// soon as its partial sum exceeds min(match_threshold, best so far), and a shift is skipped when
// the difference of its window sums already does. MatchOrLearn starts with the previous frame's
// template and its neighbours (on a route the likely match, so the bound drops early); the
// order never changes the result: the lowest difference wins, then the lowest id, then the
// smallest |shift|. MatchOrLearn (patch, column) also skips templates whose precomputed mean
// differs from the view's by more than match_threshold + 0.005 (OpenRatSLAM's prefilter). So a
// matched view's difference is exact, but a new view's `difference` is only a lower bound
// (> threshold in practice) of its best difference. Differences() is always exact and exhaustive.
// Histogram mode skips the logarithms of a stored histogram whose cheap lower bound of the
// divergence (JeffreyDivergenceLowerBound) is above the smallest divergence so far and above
// what a refined candidate can have (the threshold, or the largest of the
// histogram_max_candidates lowest candidates once that many are known): the refined candidates
// and the reported smallest divergence stay exact.
//
// Deterministic; not thread-safe for concurrent mutation; bad images throw std::invalid_argument.

#include <opencv2/core.hpp>

#include <cstdint>
#include <span>
#include <vector>

#include "services/templates/local_view_activation.h"
#include "services/templates/proto/template_library.pb.h"
#include "services/templates/template_config.h"
#include "services/templates/view_encoding.h"
#include "services/templates/view_match.h"
#include "services/templates/window_sad.h"

namespace rslam::templates {

class TemplateLibrary {
 public:
  explicit TemplateLibrary(TemplateConfig config);  // throws ConfigError on a bad config
  TemplateLibrary(const TemplateLibrary&) = delete;
  TemplateLibrary& operator=(const TemplateLibrary&) = delete;
  TemplateLibrary(TemplateLibrary&&) = default;

  // Images: CV_8UC1 grey, or CV_8UC3 BGR / CV_8UC4 BGRA of which only the crop is converted to
  // grey (exactly what converting the whole frame with cv::COLOR_BGR(A)2GRAY first would give).
  //
  // Matches the view against every template; learns it when nothing is close enough.
  ViewMatch MatchOrLearn(const cv::Mat& image);
  // Always stores the view as a new template; returns its id (ids are 0..N-1 in learning order).
  uint32_t Learn(const cv::Mat& image);
  // Difference of the view to every template (index = id), exact (no prefilter), no learning.
  std::vector<double> Differences(const cv::Mat& image) const;

  std::size_t size() const { return means_.size(); }
  const TemplateConfig& config() const { return config_; }

  proto::TemplateLibraryState ToProto() const;
  // One stored template as it appears in ToProto() (for journaling templates one at a time).
  // Throws std::out_of_range for an id >= size().
  proto::Template TemplateToProto(uint32_t id) const;
  // Throws std::invalid_argument when the state does not fit the config (mode, sizes, encoding)
  // or is inconsistent (ids not dense, wrong pixel or histogram sizes, bad histogram values).
  static TemplateLibrary FromProto(const proto::TemplateLibraryState& state, TemplateConfig config);

 private:
  struct Best {
    uint32_t id = 0;
    int shift = 0;
    double difference = 0;
    bool found = false;
  };

  // The view laid out for shifted comparison (rows doubled when panoramic, so every wrapped
  // shift is one contiguous run; kWindowSadPadding readable bytes past the end) with prefix sums
  // of its column sums.
  struct PreparedView {
    std::vector<uint8_t> rows_buffer;
    std::vector<uint32_t> column_prefix;  // column_prefix[x] = sum of all pixels left of column x
    const uint8_t* rows = nullptr;
    int stride = 0;
    float mean = 0.0f;
    // Packed windows: each shift's first view column and pixel sum, and the set scanned.
    std::vector<int> window_offsets;
    std::vector<uint32_t> window_sums;
    ShiftedWindows windows;
  };

  uint32_t Store(const EncodedView& view);
  void PrepareView(const EncodedView& view, PreparedView& prepared) const;
  // Minimum over shifts of template `id`, or +infinity when every shift passed `bound` (a shift
  // is abandoned as soon as its partial sum does). lower_bound (optional) gets the smallest
  // difference or partial difference seen: the template's difference is at least that.
  double TemplateDifference(const PreparedView& view, uint32_t id, double bound, int& best_shift,
                            double* lower_bound = nullptr) const;
  Best BestGridMatch(const PreparedView& view, bool prefilter) const;
  Best BestHistogramMatch(const EncodedView& view, double& best_divergence) const;
  // view_columns: the view's columns, column-major, each zero-padded to a multiple of 16 bytes.
  double RotationDifference(const std::vector<uint8_t>& view_columns, uint32_t id, int& best_rotation) const;
  double ShiftToAngle(int shift) const;

  const TemplateConfig config_;
  const ViewEncoder encoder_;
  const bool histogram_mode_;
  const int width_;
  const int height_;
  const int template_size_;
  struct ShiftWindow {
    int shift;
    int template_x0;
    int view_x0;
    int length;
    double sad_per_difference;  // 255 * pixels compared
  };
  static std::vector<ShiftWindow> MakeShiftWindows(const TemplateConfig& config, int width, int height);
  static std::vector<uint8_t> MakeDeadColumns(const TemplateConfig& config, int width);
  static bool WindowsShareTemplateColumns(const std::vector<ShiftWindow>& windows);
  void AppendMatchRows(const uint8_t* pixels);
  const std::vector<ShiftWindow> windows_;  // one per shift tried, smallest |s| first (column, patch)
  const std::vector<uint8_t> dead_column_;  // histogram mode: 1 where the dead zone is
  // Matching layout (column, patch): per template `height_` rows of match_row_stride_ bytes.
  // When every shift compares the same template columns (patch, panoramic), a row holds only
  // those columns, zero-padded to whole 32-byte vectors (match_x0_ = their first column);
  // otherwise (column mode) it holds the whole template row and match_x0_ = 0.
  const bool packed_windows_;
  const int match_x0_;
  const int match_row_stride_;
  const WindowSadFunction window_sad_;
  const ShiftedWindowsFunction shifted_windows_sad_;

  std::vector<uint8_t> pixels_;             // size() * template_size_, as saved
  std::vector<uint8_t> match_pixels_;       // size() * height_ * match_row_stride_ + kWindowSadPadding
  // Where MatchOrLearn starts searching: the previous frame's template (then its neighbours),
  // the likeliest match on a route. The order changes how soon the search bound tightens,
  // never the result (ties go to the lowest id whatever the order).
  uint32_t search_hint_ = 0;
  std::vector<float> means_;                // per template
  // Per template, prefix sums of its column sums (width + 1 each): the sum over any column
  // window in O(1), and |window sum difference| is a lower bound of the window's SAD, so most
  // shifts of a dissimilar template are rejected without touching its pixels.
  std::vector<uint32_t> column_prefix_;
  std::vector<float> histograms_;           // histogram mode: size() * bins
  std::vector<double> histogram_self_terms_;  // JeffreySelfTerm per template
  EncodedView scratch_;                     // reused each frame: no per-frame allocation
  PreparedView scratch_prepared_;
};

}  // namespace rslam::templates
