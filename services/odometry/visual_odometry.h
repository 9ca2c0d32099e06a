#pragma once
// Visual odometry from column-intensity profiles (Milford & Wyeth 2008, paper 000 eqs. 4-7),
// behaving like OpenRatSLAM's visual_odometry.
//
// Each frame, two crops of the grey image (one for rotation, one for speed) are reduced to 1-D
// column-intensity profiles: column means of the crop, in [0, 1]. Each profile is compared with
// the previous frame's profile over shifts s by the mean absolute difference f(s) (eq. 4):
//
//   rotation:  s_m = argmin_s f(s) over the rotation profile (eq. 5, 7);
//              dtheta = s_m * camera_fov / image_width;  vrot = dtheta / dt
//              (subpixel_rotation: s_m refined below a pixel by a V fitted through f(s_m +- 1))
//   speed:     v = f(s_m) over the speed profile at its own best shift (eq. 6), then
//              vtrans = min(max(v - vtrans_noise_floor, 0) * vtrans_scaling / (camera_hz * dt),
//                           vtrans_max)
//
// At the nominal rate (dt = 1 / camera_hz) vtrans is exactly OpenRatSLAM's
// min(v * vtrans_scaling, vtrans_max); a frame that arrives late (dropped frames) has seen
// proportionally more image change, so dividing by dt keeps the speed, not the distance, right.
// The noise floor makes a stationary camera report ~0 m/s (OpenRatSLAM drifts at standstill).
// With normalise_profile_brightness, f(s) first scales the previous profile's overlap to the
// current overlap's mean (a per-shift exposure gain), so an exposure change alone is not speed;
// a pure rotation still gives f(s_m) = 0 because the two overlaps then hold the same columns.
//
// Sign convention: shift s > 0 means the current profile is the previous one moved towards
// larger x (scene moved right in the image), which is what a camera turning left
// (counter-clockwise seen from above) sees. vrot > 0 is therefore a counter-clockwise turn
// (right-handed, z up), as in ROS.
//
// Wheel odometry: this class only does vision. A node that has wheel odometry may publish wheel
// velocities (vtrans, vrot) instead of, or blended with, these estimates; nothing downstream
// cares where the velocity came from.
//
// Speed: column sums run down 16 columns at a time in 16-bit SSE2 lanes (exact); the shift
// search takes each overlap's sums for the gain from prefix sums (double) and abandons a shift
// as soon as its running sum shows it cannot beat the best so far (the result is the same
// argmin; f of the winner is always complete). About 10-20 us a frame at St Lucia settings.
//
// Bad input (empty image, not CV_8UC1/3/4, size change mid-stream, crop outside the image, dt not
// finite or <= 0) throws std::invalid_argument with the reason; the state is left unchanged.

#include <opencv2/core.hpp>

#include <optional>
#include <span>
#include <vector>

#include "services/odometry/visual_odometry_config.h"

namespace rslam::odometry {

struct Velocity {
  double vtrans = 0.0;        // m/s (perceptual speed, scaled), >= 0
  double vrot = 0.0;          // rad/s, > 0 counter-clockwise
  int rotation_shift_px = 0;  // s_m of the rotation profile (eq. 7)
  double speed_difference = 0.0;  // v of eq. 6 before noise floor and scaling
};

// f(s) of eq. 4: mean absolute difference between current[n + s] and previous[n] over the
// overlap of the two profiles (w - |s| entries). Profiles must have equal length > |s|.
// match_gain: previous is first scaled by sum(current overlap) / sum(previous overlap).
double ShiftedProfileDifference(std::span<const float> current, std::span<const float> previous, int shift,
                                bool match_gain = false);

struct ProfileMatch {
  int shift = 0;           // argmin_s f(s) (eq. 7); ties go to the smaller |s|
  double difference = 0;   // f(shift) (eq. 6)
};

// The largest |s| BestProfileShift tries on profiles `width` long: |s| <= max_shift with
// width - |s| > min_overlap (0 when none is).
int LargestSearchedShift(int width, int max_shift, int min_overlap);

// Searches |s| <= LargestSearchedShift(w, max_shift, min_overlap), smallest |s| first so equal
// differences prefer no motion.
ProfileMatch BestProfileShift(std::span<const float> current, std::span<const float> previous, int max_shift,
                              int min_overlap, bool match_gain = false);

// Column means of grey(crop) divided by 255, written to profile (resized to the crop width).
void ColumnIntensityProfile(const cv::Mat& grey, const cv::Rect& crop, std::vector<float>& profile);

// Columns of equal azimuth over a crop of a pinhole image (equal_angle_columns): the camera's
// model is the simulator's and the floor odometry's, pixel (u, v) looking along x = (u + 0.5 -
// width / 2) / f right and y = (v + 0.5 - height / 2) / f down of the axis, f = width / 2 /
// tan(fov / 2), the axis tilted down by tilt_rad, so its azimuth is atan(x / (cos t - y sin t)):
// a row above the image's centre spans a little less azimuth than the centre row. As many columns
// as the crop's pixel columns, spanning the azimuths every row of the crop sees.
struct EqualAngleColumns {
  int count = 0;                // columns
  double rad_per_column = 0.0;  // the azimuth between neighbours
  std::vector<double> at_px;    // row by row (the crop's rows), where each column lies in the crop's pixel columns
};
// Throws std::invalid_argument unless the crop (2 or more columns) lies inside the image, fov_rad
// is in (0, pi) and |tilt_rad| < pi / 2.
EqualAngleColumns MakeEqualAngleColumns(cv::Size image, double fov_rad, double tilt_rad, const cv::Rect& crop);

// The profile over those columns of grey_crop (CV_8UC1, the crop's size): each row read at its
// columns by linear interpolation, the rows' mean divided by 255.
void EqualAngleProfile(const cv::Mat& grey_crop, const EqualAngleColumns& columns, std::vector<float>& profile);

class VisualOdometry {
 public:
  explicit VisualOdometry(VisualOdometryConfig config);  // throws ConfigError on a bad config
  VisualOdometry(const VisualOdometry&) = delete;
  VisualOdometry& operator=(const VisualOdometry&) = delete;
  VisualOdometry(VisualOdometry&&) = default;

  // Velocity between the previous frame and this one; the first frame (and the first after
  // Reset) returns zero. image: CV_8UC1 grey, or CV_8UC3 BGR / CV_8UC4 BGRA, the same size every
  // frame; a colour frame gives exactly what its cv::COLOR_BGR(A)2GRAY conversion gives, but
  // only the two crops are converted (about a third of a 640x480 St Lucia frame). dt_s: time
  // since the previous frame, finite and > 0 (ignored for the first frame but still checked).
  Velocity Update(const cv::Mat& image, double dt_s);

  // Forgets the previous frame and the image size (e.g. after a camera change).
  void Reset();

  const VisualOdometryConfig& config() const { return config_; }

 private:
  void CheckImage(const cv::Mat& image) const;
  // The crop in grey: a view of a grey image, else only the crop converted (into crop_grey_).
  cv::Mat GreyCrop(const cv::Mat& image, const cv::Rect& crop);
  // The crop's column-intensity profile.
  void CropProfile(const cv::Mat& image, const cv::Rect& crop, std::vector<float>& profile);
  // The rotation crop's profile: over columns of equal azimuth (equal_angle_columns), then
  // smoothed (rotation_profile_smoothing_px).
  void RotationProfile(const cv::Mat& image, std::vector<float>& profile);

  const VisualOdometryConfig config_;
  cv::Size image_size_{0, 0};  // fixed by the first frame
  cv::Rect vtrans_crop_;
  cv::Rect vrot_crop_;
  bool has_previous_ = false;
  // The rotation shifts of the last two frames while they were turns on the spot (turn_continuity_px).
  std::optional<double> turning_shift_px_, turning_shift_before_px_;
  // The last shift of the running turn on the spot whose halves agreed (turn_continuity_agreed_rate).
  std::optional<double> agreed_turn_shift_px_;
  std::vector<float> vtrans_profile_, vtrans_previous_;
  std::vector<float> vrot_profile_, vrot_previous_;
  // The turn each column of the rotation profile stands for (rad), and with equal_angle_columns
  // the rotation crop's columns of equal azimuth (fixed by the first frame).
  double rad_per_column_ = 0.0;
  EqualAngleColumns equal_angle_;
  cv::Mat crop_grey_;  // a colour frame's crop converted to grey (reused from frame to frame)
};

}  // namespace rslam::odometry
