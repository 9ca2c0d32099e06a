#pragma once
// Subscriber<T>: receives one message type on one topic, from this robot's partition, from one
// named robot, or from every robot ("*"). Two ways to use it:
//   - take: Wait() then Take() on the caller's thread;
//   - callback: pass a callback, and a thread of the subscriber calls it for every message in
//     arrival order.
// A sample that does not parse as T is counted in rejected(), logged once, and dropped.

#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "common/bus/participant.h"
#include "common/bus/topics.h"
#include "common/bus/typed_cdr.h"

namespace rslam::bus {

inline constexpr const char* kAllRobots = "*";

template <Message T>
class Subscriber {
 public:
  using Callback = std::function<void(const T&)>;

  // partition: empty = this participant's robot; a robot id; or kAllRobots.
  Subscriber(Participant& participant, const Topic<T>& topic, std::string partition = {})
      : participant_(participant),
        topic_name_(topic.name),
        reader_(participant.CreateRawReader(TopicSpec{std::string(topic.name), MessageTraits<T>::kTypeName,
                                                      KeyReaderFor<T>(), topic.qos,
                                                      partition.empty() ? participant.robot_id() : partition,
                                                      CodecFor<T>()})) {
    participant_.Track(topic_name_, reader_.get());
  }

  Subscriber(Participant& participant, const Topic<T>& topic, Callback callback, std::string partition = {})
      : Subscriber(participant, topic, std::move(partition)) {
    callback_ = std::move(callback);
    thread_ = std::thread([this] { Dispatch(); });
  }

  ~Subscriber() {
    stop_ = true;
    reader_->Interrupt();
    if (thread_.joinable()) thread_.join();
    participant_.Untrack(reader_.get());
  }

  Subscriber(const Subscriber&) = delete;
  Subscriber& operator=(const Subscriber&) = delete;

  bool Wait(std::chrono::milliseconds timeout) { return reader_->Wait(timeout); }

  // Up to max well-formed messages, in arrival order.
  std::vector<T> Take(std::size_t max = 256) {
    raw_.clear();
    reader_->Take(raw_, max);
    std::vector<T> out;
    out.reserve(raw_.size());
    for (auto& sample : raw_) {
      if (auto msg = Parse(sample)) out.push_back(std::move(*msg));
    }
    return out;
  }

  // Waits up to timeout for one message.
  std::optional<T> TakeOne(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
      raw_.clear();
      if (reader_->Take(raw_, 1) == 1) {
        if (auto msg = Parse(raw_.front())) return msg;
        continue;
      }
      const auto now = std::chrono::steady_clock::now();
      if (now >= deadline) return std::nullopt;
      reader_->Wait(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now) +
                    std::chrono::milliseconds(1));
    }
  }

  int MatchedPublishers() const { return reader_->MatchedWriters(); }
  bool WaitForPublishers(int n, std::chrono::milliseconds timeout) const {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (reader_->MatchedWriters() < n) {
      if (std::chrono::steady_clock::now() >= deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));  // DDS offers no wait on matching here
    }
    return true;
  }

  uint64_t received() const { return received_; }
  uint64_t rejected() const { return rejected_; }

 private:
  std::optional<T> Parse(RawSample& sample) {
    if (sample.message) {  // decoded by the vendor as it arrived
      ++received_;
      return std::move(*static_cast<T*>(sample.message.get()));
    }
    try {
      T msg = FromCdr<T>(sample.cdr);
      ++received_;
      return msg;
    } catch (const CdrError& e) {
      if (rejected_++ == 0) spdlog::warn("{}: dropped a malformed message ({}); counting further ones", topic_name_, e.what());
      return std::nullopt;
    }
  }

  void Dispatch() {
    std::vector<RawSample> batch;
    while (!stop_) {
      if (!reader_->Wait(std::chrono::milliseconds(200))) continue;
      batch.clear();
      reader_->Take(batch, 64);
      for (auto& sample : batch) {
        if (stop_) return;
        if (auto msg = Parse(sample)) callback_(*msg);
      }
    }
  }

  Participant& participant_;
  const std::string topic_name_;
  std::unique_ptr<RawReader> reader_;
  std::vector<RawSample> raw_;
  Callback callback_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> received_{0};
  std::atomic<uint64_t> rejected_{0};
  std::thread thread_;
};

}  // namespace rslam::bus
