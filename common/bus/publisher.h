#pragma once
// Publisher<T>: publishes one message type on one topic, in this robot's partition.

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "common/bus/participant.h"
#include "common/bus/topics.h"
#include "common/bus/typed_cdr.h"

namespace rslam::bus {

template <Message T>
class Publisher {
 public:
  Publisher(Participant& participant, const Topic<T>& topic)
      : participant_(participant),
        writer_(participant.CreateRawWriter(TopicSpec{std::string(topic.name), MessageTraits<T>::kTypeName,
                                                      KeyReaderFor<T>(), topic.qos, participant.robot_id()})) {
    participant_.Track(std::string(topic.name), writer_.get());
  }
  ~Publisher() { participant_.Untrack(writer_.get()); }
  Publisher(const Publisher&) = delete;
  Publisher& operator=(const Publisher&) = delete;

  // Thread-safe. Throws BusError if a reliable reader stays blocked beyond the preset's limit.
  void Publish(const T& msg) {
    std::lock_guard lock(mutex_);
    // Serialized straight into a buffer the vendor may keep (Cyclone: no copy on the way).
    std::vector<uint8_t> buffer = writer_->AcquireBuffer();
    buffer.clear();
    AppendCdr(msg, buffer);
    writer_->WriteOwned(std::move(buffer));
    ++published_;
  }

  uint64_t published() const { return published_; }

  int MatchedSubscribers() const { return writer_->MatchedReaders(); }

  // Waits until at least n readers matched (discovery takes 0.1-1.2 s on loopback).
  bool WaitForSubscribers(int n, std::chrono::milliseconds timeout) const {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (writer_->MatchedReaders() < n) {
      if (std::chrono::steady_clock::now() >= deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));  // DDS offers no wait on matching here
    }
    return true;
  }

  bool WaitForAcknowledgments(std::chrono::milliseconds timeout) { return writer_->WaitForAcknowledgments(timeout); }

 private:
  Participant& participant_;
  std::unique_ptr<RawWriter> writer_;
  std::mutex mutex_;
  std::atomic<uint64_t> published_{0};
};

}  // namespace rslam::bus
