#pragma once
// Configuration of TemplateLibrary (YAML section `templates:`). Patch-mode keys follow
// OpenRatSLAM's local view settings (image_crop_*, template_*_size, vt_*), without the prefix.

#include <cstdint>
#include <string>
#include <vector>

#include "common/config/config_error.h"

namespace rslam::templates {

struct TemplateConfig {
  // "column": 1-D column-intensity arrays (paper 000 eq. 8).
  // "patch": 2-D low-resolution templates as OpenRatSLAM.
  // "histogram": 64-bin greyscale histograms + 36-step rotation recovery (paper 001).
  std::string mode = "patch";

  // The part of the grey image used (for `histogram`: the panoramic image). -1 = image edge.
  int image_crop_x_min = 40;
  int image_crop_x_max = 600;
  int image_crop_y_min = 150;
  int image_crop_y_max = 300;

  // column/patch: the crop is area-resized to template_x_size x template_y_size
  // (column mode uses template_x_size only, one row).
  int template_x_size = 60;
  int template_y_size = 10;
  // > 0: scale the template so its mean is this value, then clip to [0, 1] (vt_normalisation).
  double normalisation = 0.4;
  // > 0: replace each pixel by (p - local mean) / local std over a (2r+1)^2 patch, mapped to
  // [0, 1] as (z + 3) / 6 (vt_patch_normalise, radius r).
  int patch_normalisation = 0;
  double min_patch_normalisation_std = 0.0;  // below it the pixel becomes 0.5
  int shift_match = 5;    // columns shifted each way when matching (non-panoramic)
  int step_match = 1;     // shift step
  bool panoramic = false; // the crop spans 360 degrees: match every wrapped shift
  // Horizontal field of view the crop spans (non-panoramic), to turn shifts into angles.
  double crop_fov_deg = 46.4;  // St Lucia: 560 of 640 columns of a 53 degree camera
  // Mean absolute difference (intensities in [0, 1]) above which a view is new (vt_match_threshold).
  double match_threshold = 0.085;
  // Skip a template whose mean differs from the view's by more than match_threshold + 0.005
  // (OpenRatSLAM's cheap prefilter; only MatchOrLearn uses it).
  bool mean_prefilter = true;

  // histogram mode (paper 001)
  int histogram_bins = 64;
  // Jeffrey divergence (001 eq. 1) of histograms normalised to sum 1, natural log; range
  // [0, 2 ln 2]. The paper's 300 is in unnormalised pixel counts of its 560x52 panoramic image:
  // 300 / 29120 ~= 0.0103 in these units.
  double histogram_divergence_threshold = 0.0103;
  bool histogram_normalise_intensity = true;  // stretch the crop to the full 0..255 range first
  int rotation_image_width = 36;   // columns of the rotation image = rotation steps (10 degrees)
  int rotation_image_height = 28;
  std::vector<int> dead_zone_columns = {};  // rotation-image columns hidden by the mirror support
  // Mean absolute difference per compared pixel (intensities in [0, 1]) above which the best
  // rotation is not a match and the view is learnt (paper: SAD < 150). 1 disables.
  double rotation_sad_threshold = 1.0;
  int histogram_max_candidates = 8;  // lowest-divergence candidates refined by rotation SAD

  template <class V>
  void VisitFields(V& v) {
    v("mode", mode, "column | patch | histogram");
    v("image_crop_x_min", image_crop_x_min, "crop, first column");
    v("image_crop_x_max", image_crop_x_max, "crop, one past the last column (-1 = image width)");
    v("image_crop_y_min", image_crop_y_min, "crop, first row");
    v("image_crop_y_max", image_crop_y_max, "crop, one past the last row (-1 = image height)");
    v("template_x_size", template_x_size, "template columns (column, patch)");
    v("template_y_size", template_y_size, "template rows (patch)");
    v("normalisation", normalisation, "> 0: scale the template to this mean (vt_normalisation); 0 off");
    v("patch_normalisation", patch_normalisation, "> 0: local patch normalisation radius (vt_patch_normalise)");
    v("min_patch_normalisation_std", min_patch_normalisation_std, "local std below which a pixel becomes 0.5");
    v("shift_match", shift_match, "columns shifted each way when matching (vt_shift_match)");
    v("step_match", step_match, "shift step (vt_step_match)");
    v("panoramic", panoramic, "crop spans 360 degrees: wrap-around matching (vt_panoramic)");
    v("crop_fov_deg", crop_fov_deg, "horizontal field of view of the crop, degrees (non-panoramic)");
    v("match_threshold", match_threshold, "column/patch: mean absolute difference above which a view is new");
    v("mean_prefilter", mean_prefilter, "skip templates whose mean differs by more than the threshold");
    v("histogram_bins", histogram_bins, "histogram mode: number of grey bins");
    v("histogram_divergence_threshold", histogram_divergence_threshold,
      "histogram mode: Jeffrey divergence (normalised histograms, ln) above which a view is new");
    v("histogram_normalise_intensity", histogram_normalise_intensity,
      "histogram mode: stretch the crop to 0..255 before the histogram");
    v("rotation_image_width", rotation_image_width, "histogram mode: rotation steps (columns) of the panorama");
    v("rotation_image_height", rotation_image_height, "histogram mode: rows of the rotation image");
    v("dead_zone_columns", dead_zone_columns, "histogram mode: rotation-image columns never compared");
    v("rotation_sad_threshold", rotation_sad_threshold,
      "histogram mode: mean absolute difference per pixel above which the rotation match fails");
    v("histogram_max_candidates", histogram_max_candidates, "histogram mode: candidates refined by SAD");
  }

  void Validate() const {
    Require(mode == "column" || mode == "patch" || mode == "histogram", "mode",
            "must be column, patch or histogram, got '" + mode + "'");
    Require(image_crop_x_min >= 0, "image_crop_x_min", "must be >= 0");
    Require(image_crop_y_min >= 0, "image_crop_y_min", "must be >= 0");
    Require(image_crop_x_max == -1 || image_crop_x_max > image_crop_x_min, "image_crop_x_max",
            "must be -1 or greater than image_crop_x_min");
    Require(image_crop_y_max == -1 || image_crop_y_max > image_crop_y_min, "image_crop_y_max",
            "must be -1 or greater than image_crop_y_min");
    Require(template_x_size >= 1 && template_x_size <= 4096, "template_x_size", "must be in 1..4096");
    Require(template_y_size >= 1 && template_y_size <= 4096, "template_y_size", "must be in 1..4096");
    Require(static_cast<int64_t>(template_x_size) * template_y_size <= (1 << 20), "template_y_size",
            "template_x_size * template_y_size must be at most 1048576 pixels");
    Require(normalisation >= 0 && normalisation <= 1, "normalisation", "must be in [0, 1]");
    Require(patch_normalisation >= 0, "patch_normalisation", "must be >= 0");
    Require(min_patch_normalisation_std >= 0, "min_patch_normalisation_std", "must be >= 0");
    Require(shift_match >= 0, "shift_match", "must be >= 0");
    Require(panoramic || mode == "histogram" || 2 * shift_match < template_x_size, "shift_match",
            "2 * shift_match must be smaller than template_x_size");
    Require(step_match >= 1, "step_match", "must be >= 1");
    Require(crop_fov_deg > 0 && crop_fov_deg <= 360, "crop_fov_deg", "must be in (0, 360]");
    Require(match_threshold >= 0, "match_threshold", "must be >= 0");
    Require(histogram_bins >= 2 && histogram_bins <= 256, "histogram_bins", "must be in 2..256");
    Require(histogram_divergence_threshold >= 0, "histogram_divergence_threshold", "must be >= 0");
    Require(rotation_image_width >= 1 && rotation_image_width <= 1024, "rotation_image_width", "must be in 1..1024");
    Require(rotation_image_height >= 1 && rotation_image_height <= 1024, "rotation_image_height",
            "must be in 1..1024");
    for (int c : dead_zone_columns) {
      Require(c >= 0 && c < rotation_image_width, "dead_zone_columns", "each column must be in [0, rotation_image_width)");
    }
    Require(static_cast<int>(dead_zone_columns.size()) < rotation_image_width, "dead_zone_columns",
            "cannot hide every column");
    Require(rotation_sad_threshold >= 0, "rotation_sad_threshold", "must be >= 0");
    Require(histogram_max_candidates >= 1, "histogram_max_candidates", "must be >= 1");
  }
};

}  // namespace rslam::templates
