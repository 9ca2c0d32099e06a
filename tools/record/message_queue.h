#pragma once
// A bounded multi-producer, single-consumer queue of received messages, bounded in bytes: the
// reader threads (one per topic) push what they take from DDS, the writer thread pops it all at
// once. A full queue refuses the message and counts it as dropped, so a disk slower than the bus
// shows up as a number instead of stalling DDS.

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <vector>

namespace rslam::record {

struct ReceivedMessage {
  std::size_t topic_index = 0;     // into the recorder's topic list
  std::string robot;
  std::vector<uint8_t> cdr;
  uint64_t log_time_ns = 0;        // receive time
  uint64_t publish_time_ns = 0;    // DDS source timestamp
};

class MessageQueue {
 public:
  explicit MessageQueue(std::size_t max_bytes) : max_bytes_(max_bytes) {}
  MessageQueue(const MessageQueue&) = delete;
  MessageQueue& operator=(const MessageQueue&) = delete;

  // False (and counted in dropped()) when the message does not fit.
  bool Push(ReceivedMessage&& message) {
    const std::size_t size = message.cdr.size() + sizeof(ReceivedMessage);
    {
      std::lock_guard lock(mutex_);
      if (bytes_ + size > max_bytes_ && !items_.empty()) {
        ++dropped_;
        return false;
      }
      bytes_ += size;
      if (bytes_ > peak_bytes_) peak_bytes_ = bytes_;
      items_.push_back(std::move(message));
    }
    cv_.notify_one();
    return true;
  }

  // Moves everything queued into out (after clearing it), waiting up to timeout for something.
  void PopAll(std::deque<ReceivedMessage>& out, std::chrono::milliseconds timeout) {
    out.clear();
    std::unique_lock lock(mutex_);
    cv_.wait_for(lock, timeout, [&] { return !items_.empty() || woken_; });
    woken_ = false;
    out.swap(items_);
    bytes_ = 0;
  }

  // Wakes a consumer blocked in PopAll.
  void Wake() {
    {
      std::lock_guard lock(mutex_);
      woken_ = true;
    }
    cv_.notify_all();
  }

  uint64_t dropped() const {
    std::lock_guard lock(mutex_);
    return dropped_;
  }
  std::size_t peak_bytes() const {
    std::lock_guard lock(mutex_);
    return peak_bytes_;
  }

 private:
  const std::size_t max_bytes_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<ReceivedMessage> items_;
  std::size_t bytes_ = 0;
  std::size_t peak_bytes_ = 0;
  uint64_t dropped_ = 0;
  bool woken_ = false;
};

}  // namespace rslam::record
