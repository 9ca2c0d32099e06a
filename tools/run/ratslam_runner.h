#pragma once
// The four RatSLAM stages in one process, one camera frame at a time: exactly the calls the
// distributed services make, in the same order and with the same arguments, so `rslam run` on a
// recording builds the same map as the services on the bus. Per frame (ProcessFrame):
//
//   grey = the frame as CV_8UC1 (cv::cvtColor BGR2GRAY; mono as is)      as camera::GreyImage
//     (only the rows the odometry and template crops cover are converted: identical crops)
//   odometry service (OdometryNode::OnImage):
//     dt = stamp - previous stamp; the first frame, a frame after a gap > max_frame_gap_s and a
//     frame of another size restart the odometry: VisualOdometry::Reset, velocity 0, dt 0
//     (Update still sees the frame, with dt = 1 / camera_hz, to keep its profile).
//     velocity = VisualOdometry::Update(grey, dt)
//   templates service (TemplatesNode::OnImage):
//     view = AsPublished(TemplateLibrary::MatchOrLearn(grey)) (view_match.h: non-finite numbers
//     are sent as finite ones)
//   pose-cell service (PoseCellsNode::ProcessFrame, velocity and view joined by frame):
//     odometry outside pose_cells.max_dt_s / max_vtrans_mps / max_vrot_radps is refused: the
//     frame then integrates no motion over min(max_dt_s, stamp difference);
//     action = PoseCellNetwork::ProcessFrame(vtrans, vrot, dt, view), sent as
//     msg::PoseCellAction (pose_cell_action_message.h) with the odometry it integrated
//   experience-map service (ExperienceMapNode::Apply), every frame's action message:
//     refused whole when its dt is beyond experience_map.max_dt_s; else
//     ExperienceMap::Integrate(vtrans, vrot, dt), then Apply(action) (an action with ids that
//     do not fit is counted and replaced by an empty one, so the correction budget is spent).
//
// Deterministic: the map depends only on the frames and their stamps. Stage times are measured
// (steady clock) but never influence the result.

#include <opencv2/core.hpp>

#include <cstdint>
#include <set>
#include <utility>

#include "services/experience_map/experience_map.h"
#include "services/odometry/visual_odometry.h"
#include "services/pose_cells/pose_cell_network.h"
#include "services/templates/template_library.h"
#include "tools/run/ratslam_config.h"

namespace rslam::run {

struct StageMicroseconds {
  double odometry = 0.0;  // includes the grey conversion
  double templates = 0.0;
  double pose_cells = 0.0;
  double experience_map = 0.0;
  double total() const { return odometry + templates + pose_cells + experience_map; }
};

// What one frame did in each stage.
struct FrameRecord {
  uint64_t frame_index = 0;  // 0, 1, 2, ... in processing order
  int64_t stamp_ns = 0;
  double dt_s = 0.0;  // 0 for the first frame
  odometry::Velocity velocity;
  templates::ViewMatch view{};
  pose_cells::Action action;
  StageMicroseconds micros;
};

// How a final relaxation ended.
struct RelaxResult {
  int sweeps = 0;  // relaxation sweeps, or Gauss-Newton steps with exp_graph_optimisation
  bool converged = false;
  double rms_link_error_m = 0.0;  // after the last batch
  double last_change_m = 0.0;     // change of rms_link_error_m over the last batch
};

// The frame as CV_8UC1: BGR (3 channels) and BGRA (4) converted, grey returned as is (no copy).
// Throws std::invalid_argument for an empty image, a depth other than 8 bits, or 2 channels.
// (Frames in ProcessFrame go through ToGreyRows, grey_rows.h: the same pixels in the rows read.)
cv::Mat ToGrey(const cv::Mat& image);

class RatSlamRunner {
 public:
  explicit RatSlamRunner(const RatSlamConfig& config);  // throws ConfigError on a bad config
  RatSlamRunner(const RatSlamRunner&) = delete;
  RatSlamRunner& operator=(const RatSlamRunner&) = delete;

  // One camera frame through the four stages. Throws std::invalid_argument on a bad image (see
  // ToGrey; nothing changed), a stamp not after the previous one (nothing changed), or an image
  // a stage cannot use (e.g. smaller than a crop: the run should stop there).
  FrameRecord ProcessFrame(const cv::Mat& image, int64_t stamp_ns);

  // The pose-cell and experience-map half of a frame, from a velocity and a view the caller
  // measured (for tools and benchmarks that prefill a map without images; the template library
  // must have learnt view.template_id already). Frames are stamped dt_s apart. Returns the pose
  // cells' action.
  pose_cells::Action IntegrateMeasurements(const odometry::Velocity& velocity, double dt_s,
                                           const templates::ViewMatch& view);
  // Learns a view as a new template without a frame (prefilling); report it to
  // IntegrateMeasurements as {id, is_new = true} on the next step.
  uint32_t LearnTemplate(const cv::Mat& image);

  // Full correction sweeps (000 eq. 3) in batches of 10 until the root-mean-square link error
  // (position, m) changes by no more than relative_tolerance of itself (or 1e-9 m) over a batch,
  // or max_sweeps. A map with inconsistent loops keeps a residual error, and its experiences can
  // keep drifting together without the links getting any better: that is converged too.
  RelaxResult RelaxToConvergence(double relative_tolerance = 1e-6, int max_sweeps = 20000);
  // Root-mean-square over links of the distance between where a link puts its target and where
  // the target is (000 eq. 3's error), metres; 0 without links.
  double RmsLinkError() const;

  const odometry::VisualOdometry& odometry() const { return odometry_; }
  const templates::TemplateLibrary& templates() const { return templates_; }
  const pose_cells::PoseCellNetwork& pose_cells() const { return pose_cells_; }
  const experience_map::ExperienceMap& experience_map() const { return map_; }
  uint64_t frames_processed() const { return frames_; }
  // kLink actions applied: places recognised and linked (loop closures).
  uint64_t loop_closures() const { return loop_closures_; }
  // Frames whose odometry the pose-cell stage refused, and actions the experience map refused
  // (as the services count them); both 0 on a healthy run.
  uint64_t refused_velocities() const { return refused_velocities_; }
  // Frames after the first on which the odometry restarted (gap beyond
  // odometry.max_frame_gap_s, or a new image size): each loses that frame's motion.
  uint64_t odometry_restarts() const { return odometry_restarts_; }
  uint64_t refused_actions() const { return refused_actions_; }
  // (from, to) of every link a loop closure created.
  const std::set<std::pair<uint32_t, uint32_t>>& loop_closure_links() const { return loop_closure_links_; }

 private:
  // The pose-cell and experience-map services' part of a frame.
  pose_cells::Action PoseCellsAndMap(double vtrans, double vrot, double dt_s, int64_t stamp_ns,
                                     const templates::ViewMatch& view);
  void ApplyToMap(const pose_cells::Action& action, double vtrans, double vrot, double dt_s);

  const RatSlamConfig config_;
  odometry::VisualOdometry odometry_;
  templates::TemplateLibrary templates_;
  pose_cells::PoseCellNetwork pose_cells_;
  experience_map::ExperienceMap map_;
  cv::Mat grey_buffer_;  // only ever written by the colour conversion; valid in the crops' rows
  uint64_t frames_ = 0;
  bool has_previous_stamp_ = false;  // odometry service
  int64_t previous_stamp_ns_ = 0;
  cv::Size previous_size_;
  bool has_last_frame_ = false;  // pose-cell service
  int64_t last_frame_stamp_ns_ = 0;
  uint64_t next_action_seq_ = 0;
  uint64_t refused_velocities_ = 0;
  uint64_t odometry_restarts_ = 0;
  uint64_t refused_actions_ = 0;
  uint64_t loop_closures_ = 0;
  int64_t synthetic_stamp_ns_ = 0;  // IntegrateMeasurements' frames
  double last_pose_cells_micros_ = 0.0;
  double last_map_micros_ = 0.0;
  std::set<std::pair<uint32_t, uint32_t>> loop_closure_links_;
};

}  // namespace rslam::run
