#pragma once
// What a service node gets from the runtime: the bus participant, its robot, where to keep
// state, and the counters its heartbeat reports (messages in, out, rejected, processing time).
// Nodes create their publishers and subscribers through it so that everything is counted.

#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"

namespace rslam {

// The runtime settings every service shares (config section "service").
struct ServiceRuntimeConfig {
  std::string state_dir;           // where state files live; empty = no persistence
  double state_save_period_s = 5;  // periodic save of stateful services (also on shutdown)
  double heartbeat_period_s = 1;   // rslam/status period
  double stop_timeout_s = 5;       // a stop (state save, bus teardown) taking longer ends the process
  bool fresh = false;              // ignore saved state at start
  std::string log_level = "info";

  template <class V>
  void VisitFields(V& v) {
    v("state_dir", state_dir, "folder for state files; empty = do not persist");
    v("state_save_period_s", state_save_period_s, "seconds between periodic state saves");
    v("heartbeat_period_s", heartbeat_period_s, "seconds between rslam/status heartbeats");
    v("stop_timeout_s", stop_timeout_s,
      "seconds a stop (saving the state, leaving the bus) may take before the process exits regardless");
    v("fresh", fresh, "start from empty state even if a state file exists");
    v("log_level", log_level, "trace, debug, info, warn, error or off");
  }
  void Validate() const;
};

class ServiceStats {
 public:
  void RecordProcessing(std::chrono::nanoseconds d);
  double mean_ms() const;
  double max_ms() const;
  uint64_t processed() const { return processed_; }

 private:
  mutable std::mutex mutex_;
  uint64_t processed_ = 0;
  double total_ms_ = 0;
  double max_ms_ = 0;
};

class ServiceContext {
 public:
  ServiceContext(std::string service, std::unique_ptr<bus::Participant> participant, ServiceRuntimeConfig runtime);
  ServiceContext(const ServiceContext&) = delete;
  ServiceContext& operator=(const ServiceContext&) = delete;

  const std::string& service() const { return service_; }
  bus::Participant& participant() { return *participant_; }
  const std::string& robot_id() const { return participant_->robot_id(); }
  const ServiceRuntimeConfig& runtime() const { return runtime_; }
  // "<state_dir>/<service>.pb", or "" when persistence is off.
  std::string StateFilePath() const;

  // A publisher whose messages are counted as "out".
  template <bus::Message T>
  std::shared_ptr<bus::Publisher<T>> Advertise(const bus::Topic<T>& topic) {
    auto pub = std::make_shared<bus::Publisher<T>>(*participant_, topic);
    std::lock_guard lock(mutex_);
    out_counters_.push_back([weak = std::weak_ptr(pub)] {
      auto p = weak.lock();
      return p ? p->published() : 0;
    });
    return pub;
  }

  // A subscriber whose callback is timed and whose messages are counted as "in" (and
  // malformed ones as "rejected"). An exception escaping the callback is counted as a rejected
  // input and logged once per kind; the service keeps running. The caller owns the subscriber:
  // destroying it stops its callbacks (the context keeps no reference).
  template <bus::Message T>
  std::shared_ptr<bus::Subscriber<T>> Subscribe(const bus::Topic<T>& topic, std::function<void(const T&)> callback,
                                                std::string partition = {}) {
    auto timed = [this, callback = std::move(callback), name = std::string(topic.name)](const T& msg) {
      const auto start = std::chrono::steady_clock::now();
      try {
        callback(msg);
      } catch (const std::exception& e) {
        Reject(name + " (exception)", e.what());
      }
      stats_.RecordProcessing(std::chrono::steady_clock::now() - start);
    };
    auto sub = std::make_shared<bus::Subscriber<T>>(*participant_, topic, std::move(timed), std::move(partition));
    std::lock_guard lock(mutex_);
    in_counters_.push_back([weak = std::weak_ptr(sub)] {
      auto s = weak.lock();
      return s ? s->received() : 0;
    });
    rejected_counters_.push_back([weak = std::weak_ptr(sub)] {
      auto s = weak.lock();
      return s ? s->rejected() : 0;
    });
    return sub;
  }

  // Counts an input the node refused (bad sizes, NaN, unknown ids...) and logs the first of
  // each kind with its reason.
  void Reject(const std::string& kind, const std::string& reason);

  uint64_t messages_in() const;
  uint64_t messages_out() const;
  uint64_t messages_rejected() const;
  ServiceStats& stats() { return stats_; }
  const ServiceStats& stats() const { return stats_; }
  // The last frame the node processed, reported in the heartbeat header.
  void SetLastFrame(uint64_t frame_seq, int64_t stamp_ns);
  std::pair<uint64_t, int64_t> last_frame() const { return {last_frame_seq_, last_stamp_ns_}; }

 private:
  static uint64_t Sum(const std::vector<std::function<uint64_t()>>& counters);

  const std::string service_;
  std::unique_ptr<bus::Participant> participant_;
  const ServiceRuntimeConfig runtime_;
  ServiceStats stats_;
  mutable std::mutex mutex_;
  std::vector<std::function<uint64_t()>> in_counters_, out_counters_, rejected_counters_;
  std::atomic<uint64_t> node_rejected_{0};
  std::set<std::string> rejected_kinds_;
  std::atomic<uint64_t> last_frame_seq_{0};
  std::atomic<int64_t> last_stamp_ns_{0};
};

}  // namespace rslam
