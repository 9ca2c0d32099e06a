#include "common/node/service_context.h"

#include <filesystem>

#include "common/config/config_error.h"

namespace rslam {

void ServiceRuntimeConfig::Validate() const {
  Require(state_save_period_s > 0, "state_save_period_s", "must be positive");
  Require(heartbeat_period_s > 0, "heartbeat_period_s", "must be positive");
  Require(stop_timeout_s > 0, "stop_timeout_s", "must be positive");
}

void ServiceStats::RecordProcessing(std::chrono::nanoseconds d) {
  const double ms = std::chrono::duration<double, std::milli>(d).count();
  std::lock_guard lock(mutex_);
  ++processed_;
  total_ms_ += ms;
  max_ms_ = std::max(max_ms_, ms);
}

double ServiceStats::mean_ms() const {
  std::lock_guard lock(mutex_);
  return processed_ ? total_ms_ / static_cast<double>(processed_) : 0.0;
}

double ServiceStats::max_ms() const {
  std::lock_guard lock(mutex_);
  return max_ms_;
}

ServiceContext::ServiceContext(std::string service, std::unique_ptr<bus::Participant> participant,
                               ServiceRuntimeConfig runtime)
    : service_(std::move(service)), participant_(std::move(participant)), runtime_(std::move(runtime)) {
  if (!runtime_.state_dir.empty()) std::filesystem::create_directories(runtime_.state_dir);
}

std::string ServiceContext::StateFilePath() const {
  if (runtime_.state_dir.empty()) return "";
  return (std::filesystem::path(runtime_.state_dir) / (service_ + ".pb")).string();
}

void ServiceContext::Reject(const std::string& kind, const std::string& reason) {
  ++node_rejected_;
  std::lock_guard lock(mutex_);
  if (rejected_kinds_.insert(kind).second)
    spdlog::warn("rejected {}: {} (further rejections of this kind are counted, not logged)", kind, reason);
}

uint64_t ServiceContext::Sum(const std::vector<std::function<uint64_t()>>& counters) {
  uint64_t total = 0;
  for (const auto& c : counters) total += c();
  return total;
}

uint64_t ServiceContext::messages_in() const {
  std::lock_guard lock(mutex_);
  return Sum(in_counters_);
}

uint64_t ServiceContext::messages_out() const {
  std::lock_guard lock(mutex_);
  return Sum(out_counters_);
}

uint64_t ServiceContext::messages_rejected() const {
  std::lock_guard lock(mutex_);
  return Sum(rejected_counters_) + node_rejected_;
}

void ServiceContext::SetLastFrame(uint64_t frame_seq, int64_t stamp_ns) {
  last_frame_seq_ = frame_seq;
  last_stamp_ns_ = stamp_ns;
}

}  // namespace rslam
