#pragma once
// Joins two message streams by the camera frame they come from (header.frame_seq). The camera
// image and the experience-map pose of one frame arrive on different topics, on different
// threads, in either order; each side waits in a small bounded buffer until its partner comes.
// Entries older than the last joined frame can never be joined (each stream is in frame order)
// and are dropped, as are the oldest entries when a buffer is full. A frame number far below the
// last joined one means the source restarted its numbering: the joiner starts over.
// Not thread-safe: the caller serialises calls.

#include <cstdint>
#include <map>
#include <optional>
#include <utility>

namespace rslam::occupancy {

template <class A, class B>
class FrameJoiner {
 public:
  struct Joined {
    uint64_t frame_seq;
    A a;
    B b;
  };

  explicit FrameJoiner(size_t capacity) : capacity_(capacity < 1 ? 1 : capacity) {}

  // Each returns the joined frame when its partner was waiting.
  std::optional<Joined> AddA(uint64_t seq, A a) {
    if (!Admit(seq)) return std::nullopt;
    if (auto it = b_.find(seq); it != b_.end()) {
      Joined joined{seq, std::move(a), std::move(it->second)};
      MarkJoined(seq);
      return joined;
    }
    Store(a_, seq, std::move(a));
    return std::nullopt;
  }

  std::optional<Joined> AddB(uint64_t seq, B b) {
    if (!Admit(seq)) return std::nullopt;
    if (auto it = a_.find(seq); it != a_.end()) {
      Joined joined{seq, std::move(it->second), std::move(b)};
      MarkJoined(seq);
      return joined;
    }
    Store(b_, seq, std::move(b));
    return std::nullopt;
  }

  // Entries thrown away (stale or overflowing) since construction.
  uint64_t dropped() const { return dropped_; }
  size_t waiting() const { return a_.size() + b_.size(); }

 private:
  bool Admit(uint64_t seq) {
    if (!last_joined_ || seq > *last_joined_) return true;
    if (*last_joined_ - seq > 2 * capacity_) {  // the source restarted its numbering
      dropped_ += a_.size() + b_.size();
      a_.clear();
      b_.clear();
      last_joined_.reset();
      return true;
    }
    ++dropped_;
    return false;
  }

  void MarkJoined(uint64_t seq) {
    last_joined_ = seq;
    dropped_ += EraseUpTo(a_, seq) + EraseUpTo(b_, seq);
  }

  template <class M, class V>
  void Store(M& m, uint64_t seq, V value) {
    m.insert_or_assign(seq, std::move(value));
    while (m.size() > capacity_) {
      m.erase(m.begin());
      ++dropped_;
    }
  }

  // Removes entries with seq' <= seq; the joined entry itself is not counted as dropped.
  template <class M>
  static uint64_t EraseUpTo(M& m, uint64_t seq) {
    uint64_t n = 0;
    while (!m.empty() && m.begin()->first <= seq) {
      if (m.begin()->first < seq) ++n;
      m.erase(m.begin());
    }
    return n;
  }

  const size_t capacity_;
  std::map<uint64_t, A> a_;
  std::map<uint64_t, B> b_;
  std::optional<uint64_t> last_joined_;
  uint64_t dropped_ = 0;
};

}  // namespace rslam::occupancy
