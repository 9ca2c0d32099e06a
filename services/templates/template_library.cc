#include "services/templates/template_library.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "common/math/angle.h"
#include "services/templates/jeffrey_divergence.h"


namespace rslam::templates {

namespace {

constexpr uint32_t kFormatVersion = 1;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// OpenRatSLAM's slack on the mean prefilter: template means are of the whole template, the
// comparison is over a shifted window, so the gap is only approximately a lower bound.
constexpr double kMeanPrefilterSlack = 0.005;

TemplateConfig Validated(TemplateConfig config) {
  config.Validate();
  return config;
}

}  // namespace

std::vector<TemplateLibrary::ShiftWindow> TemplateLibrary::MakeShiftWindows(const TemplateConfig& config, int width,
                                                                           int height) {
  std::vector<ShiftWindow> windows;
  if (config.mode == "histogram") return windows;
  // Smallest |s| first, so equal differences prefer no rotation.
  std::vector<int> shifts;
  if (config.panoramic) {
    for (int m = 0; m <= width / 2; m += config.step_match) {
      shifts.push_back(m);
      if (m != 0 && width - m != m) shifts.push_back(-m);
    }
  } else {
    for (int m = 0; m <= config.shift_match; m += config.step_match) {
      shifts.push_back(m);
      if (m != 0) shifts.push_back(-m);
    }
  }
  // Template columns [template_x0, template_x0 + length) are compared with view columns
  // shifted by s: the view's pixel at x + s against the template's at x.
  for (int s : shifts) {
    ShiftWindow w;
    w.shift = s;
    if (config.panoramic) {  // the view's rows are doubled, so a wrapped window is contiguous
      w.template_x0 = 0;
      w.view_x0 = ((s % width) + width) % width;
      w.length = width;
    } else if (config.mode == "column") {  // paper 000 eq. 8: the whole w - |s| overlap
      w.template_x0 = std::max(0, -s);
      w.view_x0 = w.template_x0 + s;
      w.length = width - std::abs(s);
    } else {  // OpenRatSLAM: the view's centre window, a constant w - 2 * shift_match columns
      w.template_x0 = config.shift_match;
      w.view_x0 = w.template_x0 + s;
      w.length = width - 2 * config.shift_match;
    }
    w.sad_per_difference = 255.0 * w.length * height;
    windows.push_back(w);
  }
  return windows;
}

std::vector<uint8_t> TemplateLibrary::MakeDeadColumns(const TemplateConfig& config, int width) {
  std::vector<uint8_t> dead(width, 0);
  if (config.mode == "histogram") {
    for (int c : config.dead_zone_columns) dead[c] = 1;
  }
  return dead;
}

bool TemplateLibrary::WindowsShareTemplateColumns(const std::vector<ShiftWindow>& windows) {
  for (const ShiftWindow& w : windows) {
    if (w.template_x0 != windows.front().template_x0 || w.length != windows.front().length) return false;
  }
  return !windows.empty();
}

TemplateLibrary::TemplateLibrary(TemplateConfig config)
    : config_(Validated(std::move(config))),
      encoder_(config_),
      histogram_mode_(config_.mode == "histogram"),
      width_(encoder_.width()),
      height_(encoder_.height()),
      template_size_(width_ * height_),
      windows_(MakeShiftWindows(config_, width_, height_)),
      dead_column_(MakeDeadColumns(config_, width_)),
      packed_windows_(WindowsShareTemplateColumns(windows_)),
      match_x0_(packed_windows_ ? windows_.front().template_x0 : 0),
      match_row_stride_(histogram_mode_ ? 0 : packed_windows_ ? (windows_.front().length + 31) / 32 * 32 : width_),
      window_sad_(BestWindowSad()),
      shifted_windows_sad_(BestShiftedWindowsSad()),
      match_pixels_(histogram_mode_ ? 0 : kWindowSadPadding, 0) {}

namespace {

// prefix[x] = sum of pixels in columns < x, for x in 0..width (prefix has width + 1 entries).
void ColumnPrefix(const uint8_t* pixels, int width, int height, int stride, uint32_t* prefix) {
  // Column sums row by row (a vectorisable loop), then the running sum.
  prefix[0] = 0;
  uint32_t* column = prefix + 1;
  std::fill(column, column + width, 0u);
  for (int y = 0; y < height; ++y) {
    const uint8_t* row = pixels + static_cast<std::size_t>(y) * stride;
    for (int x = 0; x < width; ++x) column[x] += row[x];
  }
  for (int x = 0; x < width; ++x) prefix[x + 1] += prefix[x];
}

}  // namespace

uint32_t TemplateLibrary::Store(const EncodedView& view) {
  if (size() >= std::numeric_limits<uint32_t>::max()) throw std::length_error("TemplateLibrary: too many templates");
  const auto id = static_cast<uint32_t>(size());
  pixels_.insert(pixels_.end(), view.pixels.begin(), view.pixels.end());
  means_.push_back(view.mean);
  if (histogram_mode_) {
    histograms_.insert(histograms_.end(), view.histogram.begin(), view.histogram.end());
    histogram_self_terms_.push_back(JeffreySelfTerm(view.histogram));
  } else {
    column_prefix_.resize(column_prefix_.size() + width_ + 1);
    ColumnPrefix(view.pixels.data(), width_, height_, width_, column_prefix_.data() + column_prefix_.size() - (width_ + 1));
    AppendMatchRows(view.pixels.data());
  }
  return id;
}

void TemplateLibrary::AppendMatchRows(const uint8_t* pixels) {
  // The zero padding at the end becomes the new template's first row; new padding follows it.
  const std::size_t start = match_pixels_.size() - kWindowSadPadding;
  const std::size_t template_bytes = static_cast<std::size_t>(height_) * match_row_stride_;
  match_pixels_.resize(start + template_bytes + kWindowSadPadding, 0);
  const int copied = packed_windows_ ? windows_.front().length : width_;
  for (int y = 0; y < height_; ++y) {
    std::copy_n(pixels + static_cast<std::size_t>(y) * width_ + match_x0_, copied,
                match_pixels_.data() + start + static_cast<std::size_t>(y) * match_row_stride_);
  }
}

void TemplateLibrary::PrepareView(const EncodedView& view, PreparedView& prepared) const {
  prepared.mean = view.mean;
  prepared.stride = config_.panoramic ? 2 * width_ : width_;
  prepared.rows_buffer.assign(static_cast<std::size_t>(prepared.stride) * height_ + kWindowSadPadding, 0);
  for (int y = 0; y < height_; ++y) {
    const uint8_t* row = view.pixels.data() + static_cast<std::size_t>(y) * width_;
    uint8_t* out = prepared.rows_buffer.data() + static_cast<std::size_t>(y) * prepared.stride;
    std::copy_n(row, width_, out);
    if (config_.panoramic) std::copy_n(row, width_, out + width_);
  }
  prepared.rows = prepared.rows_buffer.data();
  prepared.column_prefix.resize(prepared.stride + 1);
  ColumnPrefix(prepared.rows, prepared.stride, height_, prepared.stride, prepared.column_prefix.data());
  if (packed_windows_) {
    prepared.window_offsets.clear();
    prepared.window_sums.clear();
    for (const ShiftWindow& w : windows_) {
      prepared.window_offsets.push_back(w.view_x0);
      prepared.window_sums.push_back(prepared.column_prefix[w.view_x0 + w.length] - prepared.column_prefix[w.view_x0]);
    }
    ShiftedWindows& set = prepared.windows;
    set.view = prepared.rows;
    set.view_stride = prepared.stride;
    set.view_offsets = prepared.window_offsets.data();
    set.view_sums = prepared.window_sums.data();
    set.count = static_cast<int>(windows_.size());
    set.length = windows_.front().length;
    set.rows = height_;
    set.template_stride = match_row_stride_;
  }
}

namespace {

// The largest SAD whose difference (sad / sad_per_difference) can be within `bound`, generous by
// a relative 1e-12 so that a SAD whose difference ties the bound (computed in double) is never
// abandoned: ties are decided by the caller.
uint64_t SadLimit(double bound, double sad_per_difference) {
  const double cap = bound * sad_per_difference * (1.0 + 1e-12);
  return cap >= 4e18 ? std::numeric_limits<uint64_t>::max() : static_cast<uint64_t>(cap);
}

}  // namespace

double TemplateLibrary::TemplateDifference(const PreparedView& view, uint32_t id, double bound, int& best_shift,
                                           double* lower_bound) const {
  const uint8_t* tmpl = match_pixels_.data() + static_cast<std::size_t>(id) * height_ * match_row_stride_;
  const uint32_t* tmpl_prefix = column_prefix_.data() + static_cast<std::size_t>(id) * (width_ + 1);
  if (packed_windows_) {
    // Every shift compares the same template columns: one call scans them all.
    const ShiftWindow& w0 = windows_.front();
    const uint32_t template_sum = tmpl_prefix[w0.template_x0 + w0.length] - tmpl_prefix[w0.template_x0];
    const ShiftedWindowsResult r =
        shifted_windows_sad_(view.windows, tmpl, template_sum, SadLimit(bound, w0.sad_per_difference));
    if (lower_bound) {
      *lower_bound = std::min(*lower_bound, static_cast<double>(r.smallest_seen) / w0.sad_per_difference);
    }
    if (r.best_window < 0) return kInfinity;
    best_shift = windows_[r.best_window].shift;
    return static_cast<double>(r.best_sad) / w0.sad_per_difference;
  }
  double best = kInfinity;
  double smallest_seen = kInfinity;
  for (const ShiftWindow& w : windows_) {
    const uint64_t limit = SadLimit(std::min(best, bound), w.sad_per_difference);
    // Lower bound first: |sum(a) - sum(b)| <= sum |a - b|.
    const int64_t window_gap =
        static_cast<int64_t>(tmpl_prefix[w.template_x0 + w.length] - tmpl_prefix[w.template_x0]) -
        static_cast<int64_t>(view.column_prefix[w.view_x0 + w.length] - view.column_prefix[w.view_x0]);
    uint64_t sad = static_cast<uint64_t>(window_gap < 0 ? -window_gap : window_gap);
    if (sad <= limit) {
      sad = window_sad_(tmpl + (w.template_x0 - match_x0_), match_row_stride_, view.rows + w.view_x0, view.stride,
                        w.length, height_, limit);
    }
    // Abandoned (sad > limit), the full difference is at least the partial one: still a lower bound.
    const bool abandoned = sad > limit;
    const double difference = static_cast<double>(sad) / w.sad_per_difference;
    smallest_seen = std::min(smallest_seen, difference);
    if (!abandoned && difference < best) {
      best = difference;
      best_shift = w.shift;
    }
  }
  if (lower_bound) *lower_bound = std::min(*lower_bound, smallest_seen);
  return best;
}

TemplateLibrary::Best TemplateLibrary::BestGridMatch(const PreparedView& view, bool prefilter) const {
  Best best;
  // Only a difference within the threshold can be a match, so every template is abandoned as
  // soon as its partial sum passes the threshold (or the best so far, once one is found).
  best.difference = config_.match_threshold;
  double smallest_lower_bound = kInfinity;
  const double gap_limit = config_.match_threshold + kMeanPrefilterSlack;
  auto consider = [&](uint32_t id) {
    if (prefilter) {
      const double gap = std::abs(static_cast<double>(view.mean) - means_[id]);
      if (gap > gap_limit) {
        smallest_lower_bound = std::min(smallest_lower_bound, gap);
        return;
      }
    }
    int shift = 0;
    double lower_bound = kInfinity;
    const double difference = TemplateDifference(view, id, best.difference, shift, &lower_bound);
    // The lowest difference wins, then the lowest id: the same template whatever the order.
    const bool better = best.found ? difference < best.difference || (difference == best.difference && id < best.id)
                                   : difference <= best.difference;
    if (better) best = {id, shift, difference, true};
    smallest_lower_bound = std::min(smallest_lower_bound, lower_bound);
  };
  // The hinted template and its neighbours first (on a route the view usually matches one of
  // them, and the bound drops to its difference), then everything else in id order.
  const auto count = static_cast<uint32_t>(size());
  const uint32_t hint = std::min(search_hint_, count - 1);
  constexpr uint32_t kHintReach = 2;
  const uint32_t first = hint >= kHintReach ? hint - kHintReach : 0;
  const uint32_t end = std::min(count, hint + kHintReach + 1);
  consider(hint);
  for (uint32_t step = 1; step <= kHintReach; ++step) {
    if (hint + step < end) consider(hint + step);
    if (hint >= first + step) consider(hint - step);
  }
  // The library outgrows the core's own cache when other stages run between frames: ask for the
  // parts of a template a few ids ahead that matching reads first (its first two rows and its
  // column sums), so they arrive while the current ones are compared. Does not change results.
  constexpr uint32_t kPrefetchAhead = 4;
  const std::size_t template_bytes = static_cast<std::size_t>(height_) * match_row_stride_;
  auto prefetch = [&](uint32_t id) {
    if (id >= count) return;
    const uint8_t* pixels = match_pixels_.data() + id * template_bytes;
    __builtin_prefetch(pixels);
    __builtin_prefetch(pixels + std::min<std::size_t>(template_bytes - 1, 2 * match_row_stride_ - 1));
    const uint32_t* prefix = column_prefix_.data() + static_cast<std::size_t>(id) * (width_ + 1);
    __builtin_prefetch(prefix);
    __builtin_prefetch(prefix + width_);
  };
  for (uint32_t id = 0; id < first; ++id) {
    prefetch(id + kPrefetchAhead);
    consider(id);
  }
  for (uint32_t id = end; id < count; ++id) {
    prefetch(id + kPrefetchAhead);
    consider(id);
  }
  if (!best.found) best.difference = smallest_lower_bound;
  return best;
}

namespace {

// Column-major copy of a width x height image, each column zero-padded to `stride` bytes, the
// columns repeated `copies` times one after the other (kWindowSadPadding zero bytes follow).
void ColumnsOf(const uint8_t* pixels, int width, int height, int stride, int copies, std::vector<uint8_t>& out) {
  out.assign(static_cast<std::size_t>(width) * copies * stride + kWindowSadPadding, 0);
  for (int c = 0; c < width * copies; ++c) {
    uint8_t* column = out.data() + static_cast<std::size_t>(c) * stride;
    const int x = c % width;
    for (int y = 0; y < height; ++y) column[y] = pixels[static_cast<std::size_t>(y) * width + x];
  }
}

}  // namespace

double TemplateLibrary::RotationDifference(const std::vector<uint8_t>& view_columns, uint32_t id,
                                           int& best_rotation) const {
  // Rotating the template by r: view column x shows what template column x - r showed. The dead
  // zone is fixed to the camera, so it is masked at x in the view and at x - r in the template.
  // With the template's columns twice over in column-major order, rotation r compares the view
  // with one contiguous run (from column width - r): one SAD over all columns, minus the pairs a
  // dead column takes part in (few). Exact integers, so the same sums as column by column.
  const int stride = (height_ + 15) / 16 * 16;
  std::vector<uint8_t> template_columns;
  ColumnsOf(pixels_.data() + static_cast<std::size_t>(id) * template_size_, width_, height_, stride, 2,
            template_columns);
  auto column_sad = [&](int x, int tx) {
    return window_sad_(view_columns.data() + static_cast<std::size_t>(x) * stride, stride,
                       template_columns.data() + static_cast<std::size_t>(tx) * stride, stride, stride, 1,
                       std::numeric_limits<uint64_t>::max());
  };
  double best = kInfinity;
  for (int r = 0; r < width_; ++r) {
    uint64_t sad = window_sad_(view_columns.data(), 0, template_columns.data() + static_cast<std::size_t>(width_ - r) * stride,
                               0, width_ * stride, 1, std::numeric_limits<uint64_t>::max());
    int columns = width_;
    for (int x = 0; x < width_; ++x) {
      const int tx = (x - r + width_) % width_;
      if (dead_column_[x] || dead_column_[tx]) {
        sad -= column_sad(x, tx);
        --columns;
      }
    }
    if (columns == 0) continue;
    const double difference = static_cast<double>(sad) / (255.0 * columns * height_);
    if (difference < best) {
      best = difference;
      best_rotation = r;
    }
  }
  return best;
}

TemplateLibrary::Best TemplateLibrary::BestHistogramMatch(const EncodedView& view, double& best_divergence) const {
  const int bins = encoder_.histogram_bins();
  const double self = JeffreySelfTerm(view.histogram);
  std::vector<std::pair<double, uint32_t>> candidates;
  best_divergence = kInfinity;
  const auto count = static_cast<uint32_t>(size());
  // Only the max_candidates lowest (divergence, id) candidates are refined, so once that many
  // are known a divergence above the largest of them cannot matter (ids ascend: a tie with it
  // sorts after it). kept_divergences: those lowest divergences so far, as a max-heap.
  const std::size_t max_candidates = static_cast<std::size_t>(std::max(0, config_.histogram_max_candidates));
  std::vector<double> kept_divergences;
  kept_divergences.reserve(max_candidates);
  for (uint32_t id = 0; id < count; ++id) {
    const std::span<const float> stored(histograms_.data() + static_cast<std::size_t>(id) * bins, bins);
    // A histogram whose divergence is surely above the smallest so far and above what a kept
    // candidate can have changes nothing: skip its logarithms. The kept candidates and
    // best_divergence are exactly those of computing every divergence.
    const double candidate_limit = max_candidates == 0 ? -kInfinity
                                   : kept_divergences.size() < max_candidates
                                       ? config_.histogram_divergence_threshold
                                       : kept_divergences.front();
    if (best_divergence < kInfinity &&
        JeffreyDivergenceLowerBound(view.histogram, stored) > std::max(best_divergence, candidate_limit)) {
      continue;
    }
    const double d = JeffreyDivergenceFromSelfTerms(view.histogram, self, stored, histogram_self_terms_[id]);
    best_divergence = std::min(best_divergence, d);
    if (d <= config_.histogram_divergence_threshold) {
      candidates.emplace_back(d, id);
      if (kept_divergences.size() < max_candidates) {
        kept_divergences.push_back(d);
        std::push_heap(kept_divergences.begin(), kept_divergences.end());
      } else if (max_candidates > 0 && d < kept_divergences.front()) {
        std::pop_heap(kept_divergences.begin(), kept_divergences.end());
        kept_divergences.back() = d;
        std::push_heap(kept_divergences.begin(), kept_divergences.end());
      }
    }
  }
  const std::size_t keep = std::min<std::size_t>(candidates.size(), max_candidates);
  std::partial_sort(candidates.begin(), candidates.begin() + keep, candidates.end());
  Best best;
  double best_rotation_difference = kInfinity;
  std::vector<uint8_t> view_columns;
  if (keep > 0) ColumnsOf(view.pixels.data(), width_, height_, (height_ + 15) / 16 * 16, 1, view_columns);
  for (std::size_t i = 0; i < keep; ++i) {
    int rotation = 0;
    const double difference = RotationDifference(view_columns, candidates[i].second, rotation);
    if (difference < best_rotation_difference) {
      best_rotation_difference = difference;
      best = {candidates[i].second, rotation, candidates[i].first, true};
    }
  }
  if (best.found && best_rotation_difference > config_.rotation_sad_threshold) best.found = false;
  return best;
}

double TemplateLibrary::ShiftToAngle(int shift) const {
  if (histogram_mode_ || config_.panoramic) return WrapAngle(shift * 2.0 * std::numbers::pi / width_);
  return shift * (config_.crop_fov_deg * std::numbers::pi / 180.0) / width_;
}

ViewMatch TemplateLibrary::MatchOrLearn(const cv::Mat& image) {
  encoder_.Encode(image, scratch_);
  if (size() == 0) return {Store(scratch_), true, 0.0, kInfinity};
  if (histogram_mode_) {
    double best_divergence = kInfinity;
    const Best best = BestHistogramMatch(scratch_, best_divergence);
    if (best.found) return {best.id, false, ShiftToAngle(best.shift), best.difference};
    return {Store(scratch_), true, 0.0, best_divergence};
  }
  PrepareView(scratch_, scratch_prepared_);
  const Best best = BestGridMatch(scratch_prepared_, config_.mean_prefilter);
  if (best.found && best.difference <= config_.match_threshold) {
    search_hint_ = best.id;
    return {best.id, false, ShiftToAngle(best.shift), best.difference};
  }
  search_hint_ = Store(scratch_);
  return {search_hint_, true, 0.0, best.difference};
}

uint32_t TemplateLibrary::Learn(const cv::Mat& image) {
  encoder_.Encode(image, scratch_);
  return Store(scratch_);
}

std::vector<double> TemplateLibrary::Differences(const cv::Mat& image) const {
  EncodedView view;
  encoder_.Encode(image, view);
  std::vector<double> differences(size());
  if (histogram_mode_) {
    const int bins = encoder_.histogram_bins();
    const double self = JeffreySelfTerm(view.histogram);
    for (std::size_t id = 0; id < size(); ++id) {
      const std::span<const float> stored(histograms_.data() + id * bins, bins);
      differences[id] = JeffreyDivergenceFromSelfTerms(view.histogram, self, stored, histogram_self_terms_[id]);
    }
    return differences;
  }
  PreparedView prepared;
  PrepareView(view, prepared);
  for (std::size_t id = 0; id < size(); ++id) {
    int shift = 0;
    differences[id] = TemplateDifference(prepared, static_cast<uint32_t>(id), kInfinity, shift);
  }
  return differences;
}

proto::TemplateLibraryState TemplateLibrary::ToProto() const {
  proto::TemplateLibraryState state;
  state.set_format_version(kFormatVersion);
  state.set_mode(config_.mode);
  state.set_width(static_cast<uint32_t>(width_));
  state.set_height(static_cast<uint32_t>(height_));
  state.set_histogram_bins(static_cast<uint32_t>(encoder_.histogram_bins()));
  state.set_encoding(encoder_.description());
  for (std::size_t id = 0; id < size(); ++id) *state.add_templates() = TemplateToProto(static_cast<uint32_t>(id));
  return state;
}

proto::Template TemplateLibrary::TemplateToProto(uint32_t id) const {
  if (id >= size()) throw std::out_of_range("template " + std::to_string(id) + " of " + std::to_string(size()));
  proto::Template t;
  t.set_id(id);
  t.set_pixels(reinterpret_cast<const char*>(pixels_.data() + std::size_t{id} * template_size_), template_size_);
  if (histogram_mode_) {
    const int bins = encoder_.histogram_bins();
    const float* h = histograms_.data() + std::size_t{id} * bins;
    t.mutable_histogram()->Add(h, h + bins);
  }
  return t;
}

TemplateLibrary TemplateLibrary::FromProto(const proto::TemplateLibraryState& state, TemplateConfig config) {
  TemplateLibrary library(std::move(config));
  auto refuse = [](const std::string& reason) {
    throw std::invalid_argument("TemplateLibrary state refused: " + reason);
  };
  if (state.format_version() != kFormatVersion) {
    refuse("format_version " + std::to_string(state.format_version()) + ", expected " + std::to_string(kFormatVersion));
  }
  if (state.mode() != library.config_.mode) refuse("mode '" + state.mode() + "' but config has '" + library.config_.mode + "'");
  if (state.width() != static_cast<uint32_t>(library.width_) || state.height() != static_cast<uint32_t>(library.height_)) {
    refuse("templates are " + std::to_string(state.width()) + "x" + std::to_string(state.height()) + " but config makes " +
           std::to_string(library.width_) + "x" + std::to_string(library.height_));
  }
  const int bins = library.encoder_.histogram_bins();
  if (state.histogram_bins() != static_cast<uint32_t>(bins)) {
    refuse("histogram_bins " + std::to_string(state.histogram_bins()) + " but config has " + std::to_string(bins));
  }
  if (state.encoding() != library.encoder_.description()) {
    refuse("templates were made by '" + state.encoding() + "', config makes '" + library.encoder_.description() + "'");
  }
  EncodedView view;
  for (int i = 0; i < state.templates_size(); ++i) {
    const proto::Template& t = state.templates(i);
    const std::string which = "template " + std::to_string(i);
    if (t.id() != static_cast<uint32_t>(i)) refuse(which + " has id " + std::to_string(t.id()) + " (ids must be 0..N-1 in order)");
    if (t.pixels().size() != static_cast<std::size_t>(library.template_size_)) {
      refuse(which + " has " + std::to_string(t.pixels().size()) + " pixels, expected " +
             std::to_string(library.template_size_));
    }
    view.pixels.assign(t.pixels().begin(), t.pixels().end());
    uint32_t total = 0;
    for (uint8_t p : view.pixels) total += p;
    view.mean = static_cast<float>(total) / (255.0f * static_cast<float>(view.pixels.size()));
    if (library.histogram_mode_) {
      if (t.histogram_size() != bins) {
        refuse(which + " has " + std::to_string(t.histogram_size()) + " histogram bins, expected " + std::to_string(bins));
      }
      double sum = 0;
      for (float v : t.histogram()) {
        if (!std::isfinite(v) || v < 0) refuse(which + " has a negative or non-finite histogram entry");
        sum += v;
      }
      if (std::abs(sum - 1.0) > 1e-3) refuse(which + " histogram sums to " + std::to_string(sum) + ", not 1");
      view.histogram.assign(t.histogram().begin(), t.histogram().end());
    } else if (t.histogram_size() != 0) {
      refuse(which + " has a histogram but mode is " + library.config_.mode);
    }
    library.Store(view);
  }
  return library;
}

}  // namespace rslam::templates
