#pragma once
// Configuration of VisualOdometry (YAML section `odometry:`). Key names follow OpenRatSLAM's
// visual odometry settings so its published configurations carry over.

#include <cmath>
#include <string>

#include "common/config/config_error.h"

namespace rslam::odometry {

struct VisualOdometryConfig {
  // Speed crop: the rows below the horizon change most with forward motion (St Lucia values).
  int vtrans_image_x_min = 195;
  int vtrans_image_x_max = 475;  // exclusive; -1 = image width
  int vtrans_image_y_min = 270;
  int vtrans_image_y_max = 430;  // exclusive; -1 = image height
  // Rotation crop: the rows above the horizon, where distant scenery shifts only with rotation.
  int vrot_image_x_min = 195;
  int vrot_image_x_max = 475;
  int vrot_image_y_min = 75;
  int vrot_image_y_max = 240;
  double camera_fov_deg = 53.0;  // horizontal field of view of the whole image
  double camera_hz = 10.0;       // nominal frame rate the vtrans_scaling was tuned at
  double vtrans_scaling = 1000.0;
  double vtrans_max = 20.0;      // m/s
  int max_shift_px = 40;         // shifts |s| <= max_shift_px are searched (OpenRatSLAM: 40)
  int min_overlap_px = 30;       // a shift is tried only if w - |s| > min_overlap_px (000: |s| < w-30)
  // Mean absolute profile difference that is sensor noise, not motion: subtracted before scaling.
  double vtrans_noise_floor = 0.002;
  // Compare profiles after matching their overlap's mean (exposure gain): a global exposure
  // change then does not read as speed.
  bool normalise_profile_brightness = true;
  // A robot that turns on the spot (turn-then-drive motion, paper 003) is not moving forward:
  // at or above this rotation rate the speed is taken as 0, because perspective makes the view
  // change during a turn read as speed. 0 = off (OpenRatSLAM behaviour, for cars).
  double turn_in_place_vrot_radps = 0.0;
  // Refine the rotation shift below a pixel (a V fitted through f(s-1), f(s), f(s+1): the mean
  // absolute difference is V-shaped at its minimum). An integer shift rounds a steady turn the
  // same way every frame: 24.45 px per frame read as 24 is a 1.8% shortfall on every turn.
  bool subpixel_rotation = false;
  // Match the rotation profile's left and right halves apart; the rotation is the shift both
  // share: none when they move apart or one stands still, else the smaller. A turn moves every
  // column alike, while driving adds flow outwards in each half that grows with nearness:
  // driving at a wall the image grows (one match over the whole width finds a turn that is not
  // there, the more textured half winning, up to 0.04 rad a frame right in front of a wall), and
  // driving past a wall close on one side streams that half alone (their mean read up to 0.07
  // rad a frame, often alternating in sign, on 1% of the demo's straight frames, each also
  // zeroing the frame's speed as a turn on the spot). Turning while driving forward, the smaller
  // shift under-reads the turn by the nearer half's flow. Off: the whole crop (OpenRatSLAM).
  bool rotation_from_halves = false;
  // With rotation_from_halves, in a steady turn on the spot (the last two frames at or above
  // turn_in_place_vrot_radps, their shifts within this many pixels): halves that disagree by more
  // than this are not a drive past a wall but one half mismatched (a plain or repeating stretch of
  // wall), and the half whose shift is within this many pixels of the previous frame's is the
  // turn. Such a frame read as no turn lost the whole frame's turn, and the floor registration
  // seeded with it could read it as driving (0.36 rad lost in one turn of a demo run). 0 = off.
  double turn_continuity_px = 0.0;
  // With turn_continuity_px, the turn also goes on at the rate of its last frame whose halves
  // agreed (within turn_continuity_px; the robot turns at one rate): halves more than that apart
  // give whichever of the two halves and the whole crop's match is nearest that rate, if one is
  // within turn_continuity_px. Close beside a wall the halves' matches are poor (a turn's halves
  // there agreed in few frames in a row, so the steady turn above kept breaking) while the whole
  // crop, twice as wide, mostly still finds the turn. The rate is forgotten when a frame is no
  // turn on the spot or its halves agree on another rate (a turn's last, partial frame: driving
  // on after it, a half's flow near that rate read as the turn going on).
  bool turn_continuity_agreed_rate = false;
  // With rotation_from_halves, right after a frame read as a turn on the spot: halves that share
  // no shift (they move apart, or one stands still) give the half within this many pixels of that
  // frame's shift, if one is. Where a turn starts in front of a plain wall the halves' matches are
  // erratic for its first frames, too soon for the steady turn above (it needs two turning frames
  // within turn_continuity_px), and each frame read as no turn lost a whole frame's turn. 0 = off.
  double turn_follow_px = 0.0;
  // With turn_continuity_px, halves moving as a forward drive moves them (the left half left, the
  // right half right), both by fewer pixels than this, are not followed as the steady turn going
  // on: driving obliquely at a wall, the near half streams outwards a few pixels a frame, and once
  // a mismatched other half had read two frames as a slow turn, the steady turn followed it (AL37,
  // session 75: 15 frames of driving read as a turn on the spot). A true turn moves the half it
  // follows by its whole rate (the demo's robot: 24 px a frame). 0 = off.
  double turn_continuity_forward_px = 0.0;
  // The rotation profile is smoothed by a moving mean over this many columns each side before it
  // is matched: a wall close by at a slant shows stripes a pixel or two wide (the texture seen
  // edge-on), which a turn of a fraction of a pixel more or less changes column by column.
  int rotation_profile_smoothing_px = 0;
  // A rotation match at the edge of the search (a shift of max_shift_px, or the widest the overlap
  // allows) is no minimum: the profiles differ least as far apart as the search looks. Such a
  // match reads no turn (with rotation_from_halves, that half stands still), so max_shift_px must
  // exceed the fastest turn a frame holds (the demo's robot: 24 px a frame). Driving straight at
  // a wall close by, both halves' matches ran to the edge, and the turn continuity above held
  // it: 60 frames of 62 demo runs read 40 px (7.5 degrees), every one while the robot drove
  // straight, one run 45 degrees in six frames (tools/demo/MEASUREMENTS.md, session 55).
  bool edge_shift_reads_no_turn = false;
  // The rotation profile taken over columns of equal azimuth, for a pinhole camera of
  // camera_fov_deg across the whole image, centred on it and tilted down by camera_tilt_rad
  // (visual_odometry.h, MakeEqualAngleColumns; set from floor_odometry.camera.tilt_rad by
  // WithFloorCameraTilt, odometry_node_config.h, the one place the config gives the camera's pose):
  // its pixel columns near the edges subtend less than those at the centre (at 60 degrees, 0.75
  // times), so a turn moves texture at the edge 1.33 times as many pixels as texture at the centre,
  // and the shift a match finds reads the turn short or long as the texture lies. Over columns of
  // equal azimuth a turn moves every column alike. Off: pixel columns, each camera_fov_deg / width
  // (a panoramic camera's).
  bool equal_angle_columns = false;
  double camera_tilt_rad = 0.0;  // the camera's axis below the horizontal; not a key (above)

  template <class V>
  void VisitFields(V& v) {
    v("vtrans_image_x_min", vtrans_image_x_min, "speed crop, first column");
    v("vtrans_image_x_max", vtrans_image_x_max, "speed crop, one past the last column (-1 = image width)");
    v("vtrans_image_y_min", vtrans_image_y_min, "speed crop, first row");
    v("vtrans_image_y_max", vtrans_image_y_max, "speed crop, one past the last row (-1 = image height)");
    v("vrot_image_x_min", vrot_image_x_min, "rotation crop, first column");
    v("vrot_image_x_max", vrot_image_x_max, "rotation crop, one past the last column (-1 = image width)");
    v("vrot_image_y_min", vrot_image_y_min, "rotation crop, first row");
    v("vrot_image_y_max", vrot_image_y_max, "rotation crop, one past the last row (-1 = image height)");
    v("camera_fov_deg", camera_fov_deg,
      "horizontal field of view of the full image, degrees (with floor_odometry on: the floor camera's)");
    v("camera_hz", camera_hz, "frame rate at which vtrans_scaling gives m/s (OpenRatSLAM camera_hz)");
    v("vtrans_scaling", vtrans_scaling, "m/s per unit of mean profile difference at camera_hz");
    v("vtrans_max", vtrans_max, "upper clamp of the speed, m/s");
    v("max_shift_px", max_shift_px, "largest profile shift searched each way, pixels");
    v("min_overlap_px", min_overlap_px, "minimum overlap of two shifted profiles, pixels");
    v("vtrans_noise_floor", vtrans_noise_floor,
      "profile difference treated as noise (subtracted before scaling), so standstill gives 0");
    v("normalise_profile_brightness", normalise_profile_brightness,
      "match the exposure gain of the compared profiles so brightness changes do not read as speed");
    v("turn_in_place_vrot_radps", turn_in_place_vrot_radps,
      "rotation rate at or above which speed is 0 (robots that turn on the spot); 0 = off");
    v("subpixel_rotation", subpixel_rotation,
      "refine the rotation shift below a pixel (OpenRatSLAM: whole pixels)");
    v("rotation_from_halves", rotation_from_halves,
      "rotation = the shift the rotation crop's two halves, matched apart, share (flow only one half shows is not a turn)");
    v("turn_continuity_px", turn_continuity_px,
      "steady turn on the spot, halves this many px apart: the one this near the last shift is the turn (0 = off)");
    v("turn_continuity_agreed_rate", turn_continuity_agreed_rate,
      "a turn on the spot goes on at the rate its halves last agreed on: halves apart take the half or whole crop nearest it");
    v("turn_follow_px", turn_follow_px,
      "after a turn on the spot, halves sharing no shift: the one this near that frame's shift is the turn (0 = off)");
    v("turn_continuity_forward_px", turn_continuity_forward_px,
      "steady turn: halves moving as a forward drive moves them, both by fewer px than this, are no turn (0 = off)");
    v("edge_shift_reads_no_turn", edge_shift_reads_no_turn,
      "a rotation match at the search's edge (max_shift_px) reads no turn: the least difference lies beyond it");
    v("rotation_profile_smoothing_px", rotation_profile_smoothing_px,
      "the rotation profile is smoothed by a moving mean over this many columns each side before matching (0 = off)");
    v("equal_angle_columns", equal_angle_columns,
      "the rotation profile is taken over columns of equal azimuth (a pinhole camera of camera_fov_deg, tilted as "
      "floor_odometry.camera.tilt_rad says)");
  }

  void Validate() const {
    auto crop = [](int min, int max, const char* min_key, const char* max_key) {
      Require(min >= 0, min_key, "must be >= 0");
      Require(max == -1 || max > min, max_key, "must be -1 (image edge) or greater than " + std::string(min_key));
    };
    crop(vtrans_image_x_min, vtrans_image_x_max, "vtrans_image_x_min", "vtrans_image_x_max");
    crop(vtrans_image_y_min, vtrans_image_y_max, "vtrans_image_y_min", "vtrans_image_y_max");
    crop(vrot_image_x_min, vrot_image_x_max, "vrot_image_x_min", "vrot_image_x_max");
    crop(vrot_image_y_min, vrot_image_y_max, "vrot_image_y_min", "vrot_image_y_max");
    Require(camera_fov_deg > 0 && camera_fov_deg <= 360, "camera_fov_deg", "must be in (0, 360]");
    Require(camera_hz > 0, "camera_hz", "must be positive");
    Require(vtrans_scaling >= 0, "vtrans_scaling", "must be >= 0");
    Require(vtrans_max >= 0, "vtrans_max", "must be >= 0");
    Require(max_shift_px >= 0, "max_shift_px", "must be >= 0");
    Require(min_overlap_px >= 1, "min_overlap_px", "must be >= 1");
    Require(vtrans_noise_floor >= 0, "vtrans_noise_floor", "must be >= 0");
    Require(turn_in_place_vrot_radps >= 0, "turn_in_place_vrot_radps", "must be >= 0");
    Require(turn_continuity_px >= 0, "turn_continuity_px", "must be >= 0");
    Require(!turn_continuity_agreed_rate || (rotation_from_halves && turn_continuity_px > 0),
            "turn_continuity_agreed_rate", "needs rotation_from_halves and turn_continuity_px > 0");
    Require(turn_follow_px >= 0, "turn_follow_px", "must be >= 0");
    Require(turn_continuity_forward_px >= 0, "turn_continuity_forward_px", "must be >= 0");
    Require(turn_follow_px == 0 || rotation_from_halves, "turn_follow_px", "needs rotation_from_halves");
    Require(!equal_angle_columns || camera_fov_deg < 180, "equal_angle_columns",
            "needs a pinhole camera: camera_fov_deg under 180");
    Require(rotation_profile_smoothing_px >= 0 && rotation_profile_smoothing_px <= 64, "rotation_profile_smoothing_px",
            "must be 0..64");
  }
};

}  // namespace rslam::odometry
