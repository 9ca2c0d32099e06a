#pragma once
// Joins the two inputs of the pose cells, odometry and the local-view result, by the camera frame
// they come from (header.frame_seq), and releases frames strictly in increasing frame order.
//
// Each stream is reliable and in frame order, so once a stream has delivered frame s, it will
// never deliver a frame before s: a frame whose partner stream has moved past it is released
// with the side it has (the other side was lost or rejected). A stream that stops altogether (its
// producer died) is waited for until the live stream is `window` frames ahead AND the frame has
// waited `max_wait_ns` (both: in a burst one subscriber thread can run far ahead of the other,
// and at a low frame rate a window of frames is a long time). Times are the caller's clock. A frame number far below the last released one means the camera
// restarted its numbering: the joiner starts over. Not thread-safe: the caller serialises calls.

#include <algorithm>
#include <cstdint>
#include <map>
#include <optional>
#include <utility>
#include <vector>

namespace rslam::pose_cells {

template <class Velocity, class View>
class VelocityViewJoiner {
 public:
  struct Frame {
    uint64_t frame_seq = 0;
    std::optional<Velocity> velocity;
    std::optional<View> view;
  };

  VelocityViewJoiner(uint64_t window, int64_t max_wait_ns)
      : window_(std::max<uint64_t>(1, window)), max_wait_ns_(max_wait_ns) {}

  // Returns false (and keeps nothing) for a frame already released: a duplicate or too late.
  // now_ns: arrival time on the caller's clock.
  bool AddVelocity(uint64_t seq, Velocity v, int64_t now_ns = 0) {
    return Add(seq, &velocities_, &last_velocity_, Timed<Velocity>{std::move(v), now_ns});
  }
  bool AddView(uint64_t seq, View v, int64_t now_ns = 0) {
    return Add(seq, &views_, &last_view_, Timed<View>{std::move(v), now_ns});
  }
  // The stream delivered frame seq but its content was refused: the frame goes on without it.
  void SkipVelocity(uint64_t seq) { Note(seq, &last_velocity_); }
  void SkipView(uint64_t seq) { Note(seq, &last_view_); }

  // Frames that can be processed now (now_ns on the clock of the Add calls), in frame order.
  std::vector<Frame> TakeReady(int64_t now_ns = 0) {
    std::vector<Frame> out;
    while (true) {
      const std::optional<uint64_t> next = Earliest();
      if (!next) break;
      const uint64_t s = *next;
      auto v = velocities_.find(s);
      auto w = views_.find(s);
      const bool have_velocity = v != velocities_.end(), have_view = w != views_.end();
      if (!(have_velocity && have_view)) {
        // The missing side is lost when its stream delivered s or moved past it, or presumed lost
        // when the other stream ran `window` frames ahead.
        const std::optional<uint64_t>& missing_last = have_velocity ? last_view_ : last_velocity_;
        const std::optional<uint64_t>& present_last = have_velocity ? last_velocity_ : last_view_;
        const bool passed = missing_last && *missing_last >= s;  // delivered (or refused) and gone
        const int64_t arrived = have_velocity ? v->second.arrival_ns : w->second.arrival_ns;
        const bool ran_ahead = present_last && *present_last >= s + window_ && now_ns - arrived >= max_wait_ns_;
        if (!passed && !ran_ahead) break;
        ++incomplete_;
      }
      Frame f;
      f.frame_seq = s;
      if (have_velocity) {
        f.velocity = std::move(v->second.value);
        velocities_.erase(v);
      }
      if (have_view) {
        f.view = std::move(w->second.value);
        views_.erase(w);
      }
      released_ = s;
      out.push_back(std::move(f));
    }
    return out;
  }

  // Frames released with one side missing, and inputs dropped as duplicates or too late.
  uint64_t incomplete() const { return incomplete_; }
  uint64_t stale() const { return stale_; }
  std::optional<uint64_t> last_released() const { return released_; }
  size_t waiting() const { return velocities_.size() + views_.size(); }

 private:
  template <class T>
  struct Timed {
    T value;
    int64_t arrival_ns;
  };

  template <class T>
  bool Add(uint64_t seq, std::map<uint64_t, T>* buffer, std::optional<uint64_t>* last, T value) {
    if (!Admit(seq)) return false;
    Note(seq, last);
    (*buffer)[seq] = std::move(value);
    return true;
  }

  void Note(uint64_t seq, std::optional<uint64_t>* last) {
    if (!*last || seq > **last) *last = seq;
  }

  bool Admit(uint64_t seq) {
    if (!released_ || seq > *released_) return true;
    if (*released_ - seq > 4 * window_) {  // the camera restarted its numbering
      velocities_.clear();
      views_.clear();
      released_.reset();
      last_velocity_.reset();
      last_view_.reset();
      return true;
    }
    ++stale_;
    return false;
  }

  std::optional<uint64_t> Earliest() const {
    std::optional<uint64_t> e;
    if (!velocities_.empty()) e = velocities_.begin()->first;
    if (!views_.empty() && (!e || views_.begin()->first < *e)) e = views_.begin()->first;
    return e;
  }

  const uint64_t window_;
  const int64_t max_wait_ns_;
  std::map<uint64_t, Timed<Velocity>> velocities_;
  std::map<uint64_t, Timed<View>> views_;
  std::optional<uint64_t> last_velocity_, last_view_;  // highest frame each stream delivered
  std::optional<uint64_t> released_;
  uint64_t incomplete_ = 0;
  uint64_t stale_ = 0;
};

}  // namespace rslam::pose_cells
