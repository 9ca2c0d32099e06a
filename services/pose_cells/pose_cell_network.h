#pragma once
// The RatSLAM pose cells: a 3-D (x, y, theta) competitive attractor network that wraps in all
// three dimensions (Milford & Wyeth, paper 000 section II; OpenRatSLAM posecell_network.cpp is
// the reference behaviour), plus the experience bookkeeping that turns its state into
// create/link/set actions with explicit ids (see pose_cell_action.h).
//
// One step, per camera frame (ProcessFrame):
//   1. view injection (001 eqs. 3-4): a familiar template injects energy at its associated cell,
//      shifted in theta by the view's orientation offset gamma: theta_j = theta'_ij + gamma.
//      A new template is associated with the current best pose minus gamma (eq. 3). Repeated
//      injection of the same view decays (vt_active_decay, restored by pc_vt_restore per frame).
//   2. local excitation: activity convolved with a normalised 7^3 Gaussian (separable, so three
//      1-D passes), then local inhibition with a 5^3 Gaussian subtracted, then global inhibition
//      (subtract pc_global_inhib, clamp at 0: this also zeroes the tails), then normalise to 1.
//   3. path integration: each theta layer k (direction k * 2pi / dim_th) shifts by
//      vtrans * dt / cell size along its direction, fractional shifts split bilinearly (as
//      OpenRatSLAM's four-quadrant weights); then activity shifts in theta by vrot * dt, the
//      fraction split linearly between the two neighbouring layers.
//   4. best pose: population vector (circular mean) over +-pc_cells_to_avg cells around the peak.
//   5. action: OpenRatSLAM get_action with explicit ids; with exp_boundary_check a new link to
//      an old experience must also pass the floor-boundary check (boundary_match.h), else the
//      network makes a new experience; with exp_boundary_offset a link or set whose two
//      boundaries align carries the registered offset of the robot from the experience; with
//      exp_view_offset the offset measured from the best recent view and the odometry instead;
//      with exp_submap_offset the one registering both visits' walls, whose disagreement
//      refuses a new link under exp_submap_check.
//
// Speed: activity is compact, so every pass runs only over the product of the active index sets
// of x, y and theta (dilated by the kernel radius or the shift); buffers are preallocated and
// kept zero outside the active region, so a step allocates nothing. Each convolution pass
// gathers all taps of an output row at once (AVX2 when the CPU has it, else SSE2), adding them
// in the same order per cell as tap-by-tap passes would and without fused multiply-adds, so
// every CPU computes the same floats.

#include <Eigen/Core>

#include <cstdint>
#include <deque>
#include <optional>
#include <utility>
#include <vector>

#include "common/math/pose2d.h"
#include "services/pose_cells/boundary_match.h"
#include "services/pose_cells/pose_cell_action.h"
#include "services/pose_cells/pose_cell_config.h"
#include "services/pose_cells/proto/pose_cells_state.pb.h"
#include "services/templates/view_match.h"

namespace rslam::pose_cells {

struct PoseCellPosition {
  double x = 0.0;   // cells, [0, dim_xy)
  double y = 0.0;   // cells, [0, dim_xy)
  double th = 0.0;  // cells, [0, dim_th)
};

// A frame's floor boundary (odometry/velocity's boundary): points in the robot frame, metres.
using FloorBoundary = std::vector<Eigen::Vector2f>;

// An experience as the experience map knows it (its id is its index in the map's list): what a
// restarted pose-cell service adopts to resynchronise (AdoptExperienceMap).
struct MapExperience {
  uint32_t template_id = 0;
  PoseCellPosition cell;  // pose-cell position the experience was created at
};

using templates::ViewMatch;

class PoseCellNetwork {
 public:
  explicit PoseCellNetwork(const PoseCellConfig& config);
  PoseCellNetwork(const PoseCellNetwork&) = delete;
  PoseCellNetwork& operator=(const PoseCellNetwork&) = delete;

  // The single entry point: one call per camera frame with that frame's odometry (vtrans m/s,
  // vrot rad/s over dt s) and view match. Returns the action for the experience map.
  // boundary: the frame's floor boundary, kept with an experience made now and compared with an
  // old experience's before linking to it (exp_boundary_check); nullptr: not measured.
  // Throws std::invalid_argument (state unchanged) on non-finite or negative dt or difference,
  // non-finite velocities or angle, or a template id beyond the next expected id.
  Action ProcessFrame(double vtrans_mps, double vrot_radps, double dt_s, const ViewMatch& view,
                      const FloorBoundary* boundary = nullptr);

  // A frame whose view never arrived (the template learner restarted): path integration only.
  // The current view counts as unchanged, so nothing is injected and no view change drives the
  // decision. Throws std::invalid_argument (state unchanged) as ProcessFrame.
  Action ProcessFrameWithoutView(double vtrans_mps, double vrot_radps, double dt_s,
                                 const FloorBoundary* boundary = nullptr);

  // Resynchronisation after a restart. The experience map is the authority on experiences: it
  // may have applied actions this network never saved (it restarted from an older state) or,
  // when actions were lost, fewer. This replaces the experience bookkeeping (experiences, their
  // template associations, known links, current experience) with the map's, so the next
  // created id is the map's next id. Templates this network has not seen yet are associated
  // with the cell of their first experience (their learning cell, 001 eq. 3 without offset),
  // or recorded unplaced (SkipTemplates) when they have none; the activity packet is moved to the current experience's cell, where the robot last was.
  // Throws std::invalid_argument (network unchanged) on out-of-range cells or ids.
  // move_packet = false keeps the activity packet (a restored state knows a more recent pose).
  void AdoptExperienceMap(const std::vector<MapExperience>& experiences,
                          const std::vector<std::pair<uint32_t, uint32_t>>& links,
                          uint32_t current_experience_id, bool move_packet = true);

  // After a restart that lost frames the robot moved an unknown amount: a familiar view tells
  // where it is. Moves the activity packet to the cell the template is associated with,
  // shifted by the view's orientation offset (001 eq. 4), and returns true; returns false with
  // nothing changed when the template is unknown, unplaced or has no experience yet.
  bool RelocaliseToView(uint32_t template_id, double relative_angle_rad);

  // Templates [template_count(), next_template_id) were learnt while this network did not see
  // their views (it was down, or their frames were lost). They are recorded unplaced: the first
  // time one is seen it is associated with the then current pose, as a new template would be
  // (001 eq. 3), and injects nothing until then. Throws std::invalid_argument when
  // next_template_id is below template_count() (nothing changes).
  void SkipTemplates(uint32_t next_template_id);

  // Finer steps (ProcessFrame = InjectView, Step, DecideAction).
  void InjectView(uint32_t template_id, double relative_angle_rad, bool is_new);
  // Excite, inhibit, normalise, path-integrate by (vtrans * dt, vrot * dt), find the best pose.
  void Step(double vtrans_mps, double vrot_radps, double dt_s);
  // Only the attractor dynamics (no path integration, no best-pose update).
  void ExciteInhibitNormalise();
  void PathIntegrate(double vtrans_mps, double vrot_radps, double dt_s);
  PoseCellPosition UpdateBestPose();
  // boundary as ProcessFrame's.
  Action DecideAction(const FloorBoundary* boundary = nullptr);

  // Adds energy at one cell (wrapped); for tests and tools.
  void InjectEnergy(int x, int y, int th, double energy);

  PoseCellPosition BestPose() const { return best_; }
  float Activity(int x, int y, int th) const;
  double TotalActivity() const;
  // Number of cells with non-zero activity.
  int ActiveCellCount() const;
  // Cells in the box (product of active x, y and theta index sets) each step works on.
  int ActiveRegionCells() const {
    return static_cast<int>(xs_.index.size() * ys_.index.size() * ts_.index.size());
  }
  const PoseCellConfig& config() const { return config_; }
  uint32_t experience_count() const { return static_cast<uint32_t>(experiences_.size()); }
  uint32_t template_count() const { return static_cast<uint32_t>(views_.size()); }
  uint64_t next_sequence() const { return next_sequence_; }
  // Distance in cells between the best pose (theta corrected by the view offset) and a cell
  // position, wrapping in every dimension (OpenRatSLAM get_delta_pc).
  double DeltaPc(const PoseCellPosition& p) const;

  // 1-D normalised kernel weights (index 0 .. dim-1, centre dim/2); the 3-D kernel is their
  // outer product.
  const std::vector<float>& excite_weights() const { return excite_w_; }
  const std::vector<float>& inhibit_weights() const { return inhibit_w_; }

  proto::State SaveState() const;
  // Throws std::invalid_argument when the state does not fit this network's dimensions or is
  // inconsistent; the network is unchanged then.
  void LoadState(const proto::State& state);

 private:
  struct ViewAssociation {
    double pc_x, pc_y, pc_th;
    double decay;         // as of view update number decay_stamp
    uint64_t decay_stamp;
    std::vector<uint32_t> experience_ids;
    bool placed = true;  // false: learnt unseen (SkipTemplates), associated at its next sighting
  };
  // OpenRatSLAM subtracts pc_vt_restore from every template's decay on every view update
  // (clamped at vt_active_decay); done lazily here.
  double EffectiveDecay(const ViewAssociation& v) const;
  struct ExperienceCell {
    double pc_x, pc_y, pc_th;
    uint32_t template_id;
    uint64_t created_frame = 0;   // frames_processed_ when made
    std::optional<FloorBoundary> boundary;  // none when not measured (adopted from the map)
    std::optional<Pose2D> odometry;  // odometry_ when made; none when adopted from the map
  };
  struct RecentView {
    uint32_t template_id;
    double difference;
    Pose2D odometry;  // odometry_ at its frame
  };
  // exp_view_offset: where the robot stands in experience `recognised`'s frame (pose_cell_config.h);
  // nullopt when no recent view's template has an experience made near enough in time.
  std::optional<Eigen::Vector2d> ViewOffset(uint32_t recognised) const;
  // The two views' floor boundaries registered (boundary_match.h) when both are known and hold
  // exp_boundary_min_points points; nullopt otherwise.
  std::optional<BoundaryMatch> MatchBoundary(const ExperienceCell& e, const FloorBoundary* boundary) const;
  // exp_submap_offset: the boundaries of the experiences made within exp_submap_frames frames of
  // `recognised` registered with those of the last exp_submap_frames frames; nullopt when either
  // side holds fewer than exp_boundary_min_points points.
  std::optional<BoundaryMatch> MatchSubmaps(uint32_t recognised) const;
  // Keeps the frame's boundary (exp_submap_offset) and forgets those older than exp_submap_frames.
  void RememberBoundary(const FloorBoundary* boundary);
  bool BoundaryAligns(const BoundaryMatch& match) const;
  // Active indices along one axis: sorted list, membership mask, and maximal contiguous runs
  // [begin, end) (not wrapping), so inner loops over x are plain vectorisable ranges.
  struct AxisSet {
    std::vector<int> index;
    std::vector<uint8_t> member;
    std::vector<std::pair<int, int>> runs;
    void Reset(int n) {
      index.clear();
      runs.clear();
      member.assign(n, 0);
    }
    // Rebuilds index and runs from member.
    void Finish() {
      index.clear();
      runs.clear();
      const int n = static_cast<int>(member.size());
      for (int i = 0; i < n; ++i) {
        if (!member[i]) continue;
        index.push_back(i);
        if (!runs.empty() && runs.back().second == i) {
          ++runs.back().second;
        } else {
          runs.emplace_back(i, i + 1);
        }
      }
    }
  };

  size_t Flat(int x, int y, int th) const {
    return (static_cast<size_t>(th) * dim_xy_ + y) * dim_xy_ + x;
  }
  void Dilate(const AxisSet& in, int n, int lo, int hi, AxisSet& out) const;
  void ZeroRegion(std::vector<float>& buf, const AxisSet& xs, const AxisSet& ys, const AxisSet& ts);
  struct RowExtent;
  using RowFlags = std::vector<RowExtent>;
  // Recomputes the active sets of activity_ from scratch within the given region. candidates:
  // per row an interval outside which the row is known to be zero (an empty one: all zero), so
  // only it is scanned; nullptr scans the region's whole rows.
  void RecomputeSupport(const AxisSet& xs, const AxisSet& ys, const AxisSet& ts, const RowFlags* candidates);
  // Per (theta, y) row: an interval [lo, hi) of x that covers every non-zero cell of the row
  // (empty when lo >= hi). The passes skip empty rows and the parts of the box outside a row's
  // interval, which matter when a view injection starts a second packet far from the first.
  struct RowExtent {
    int lo = 0, hi = 0;
    bool empty() const { return lo >= hi; }
    // The hull of this and [b, e).
    void Add(int b, int e) {
      if (empty()) {
        lo = b;
        hi = e;
      } else {
        lo = lo < b ? lo : b;
        hi = hi > e ? hi : e;
      }
    }
  };
  // Kernel widths are at most the network's size (config); taps are gathered on the stack.
  static constexpr int kMaxTaps = 1001;
  void ConvolveX(const std::vector<float>& in, const RowFlags& in_rows, std::vector<float>& out,
                 RowFlags& out_rows, const std::vector<float>& w, const AxisSet& xs_out,
                 const AxisSet& ys, const AxisSet& ts);
  void ConvolveY(const std::vector<float>& in, const RowFlags& in_rows, std::vector<float>& out,
                 RowFlags& out_rows, const std::vector<float>& w, const AxisSet& xs,
                 const AxisSet& ys_in, const AxisSet& ys_out, const AxisSet& ts) const;
  void ConvolveTh(const std::vector<float>& in, const RowFlags& in_rows, std::vector<float>& out,
                  RowFlags& out_rows, const std::vector<float>& w, const AxisSet& xs,
                  const AxisSet& ys, const AxisSet& ts_in, const AxisSet& ts_out) const;
  size_t Row(int y, int th) const { return static_cast<size_t>(th) * dim_xy_ + y; }
  bool Linked(uint32_t a, uint32_t b) const;
  // All activity at one cell (as the constructor starts), best pose there.
  void PlacePacket(const PoseCellPosition& cell);
  void CreateExperience(const FloorBoundary* boundary);
  void DeadReckon(double distance_m, double turn_rad);
  void ValidateFrame(double vtrans, double vrot, double dt, const ViewMatch& view) const;

  const PoseCellConfig config_;
  const int dim_xy_;
  const int dim_th_;
  const std::vector<float> excite_w_;
  const std::vector<float> inhibit_w_;

  std::vector<float> activity_;  // zero outside (xs_, ys_, ts_)
  std::vector<float> buf_a_, buf_b_, buf_c_;  // scratch, always all zero between calls
  RowFlags rows_act_, rows_a_, rows_b_, rows_c_;  // valid inside each buffer's current region
  RowFlags rows_candidate_;  // path integration: where each moved row can be non-zero
  AxisSet xs_, ys_, ts_;                      // active region of activity_
  AxisSet ex_xs_, ex_ys_, ex_ts_, tmp_xs_, tmp_ys_, tmp_ts_;  // scratch sets

  PoseCellPosition best_;
  std::vector<ViewAssociation> views_;
  std::vector<ExperienceCell> experiences_;
  std::vector<std::vector<uint32_t>> links_of_;  // undirected adjacency of known links
  bool has_current_experience_ = false;
  uint32_t current_experience_ = 0;
  bool has_current_template_ = false;
  uint32_t current_template_ = 0;
  bool has_previous_template_ = false;
  uint32_t previous_template_ = 0;
  double view_delta_th_cells_ = 0.0;  // orientation offset of the last view, in theta cells
  uint64_t next_sequence_ = 0;
  uint64_t frames_processed_ = 0;
  uint64_t view_updates_ = 0;
  Pose2D odometry_;  // dead-reckoned pose of the odometry this network integrated (exp_view_offset)
  std::deque<RecentView> recent_views_;  // the last exp_view_offset_frames, oldest first
  struct RecentBoundary {
    uint64_t frame;    // frames_processed_ at it
    Pose2D odometry;   // odometry_ at it
    FloorBoundary points;
  };
  std::deque<RecentBoundary> recent_boundaries_;  // within the last exp_submap_frames, oldest first
  std::vector<double> avg_x_, avg_y_, avg_th_;  // population-vector sums, preallocated
  std::vector<float> padded_row_;               // ConvolveX scratch: one row with wrapped margins
};

}  // namespace rslam::pose_cells
