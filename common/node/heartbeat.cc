#include "common/node/heartbeat.h"

#include <unistd.h>

#include <algorithm>
#include <map>
#include <set>

namespace rslam {

Heartbeat::Heartbeat(ServiceContext& context)
    : context_(context),
      publisher_(context.participant(), bus::topics::kStatus),
      start_(std::chrono::steady_clock::now()) {}

void Heartbeat::Publish(const std::string& state) {
  msg::ServiceStatus s;
  const auto [frame, stamp] = context_.last_frame();
  s.header = {context_.robot_id(), frame, stamp};
  s.service = context_.service();
  s.dds_vendor = bus::VendorName(context_.participant().vendor());
  s.pid = static_cast<uint32_t>(::getpid());
  s.uptime_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  s.messages_in = context_.messages_in();
  s.messages_out = context_.messages_out();
  s.messages_rejected = context_.messages_rejected();
  s.processing_ms_mean = context_.stats().mean_ms();
  s.processing_ms_max = context_.stats().max_ms();
  s.state = state;
  for (const bus::EndpointMatchCount& e : context_.participant().Matches())
    s.endpoints.push_back({e.topic, e.writer, static_cast<uint32_t>(e.matched)});
  publisher_.Publish(s);
}

std::vector<std::string> UnmatchedLinks(const std::vector<msg::ServiceStatus>& services) {
  std::map<std::string, uint32_t> writers, readers;  // topic -> services with a writer / reader of it
  for (const msg::ServiceStatus& s : services) {
    std::set<std::string> writes, reads;
    for (const msg::EndpointMatch& e : s.endpoints) (e.writer ? writes : reads).insert(e.topic);
    for (const auto& topic : writes) ++writers[topic];
    for (const auto& topic : reads) ++readers[topic];
  }
  std::vector<std::string> unmatched;
  for (const msg::ServiceStatus& s : services) {
    for (const msg::EndpointMatch& e : s.endpoints) {
      const auto& table = e.writer ? readers : writers;
      const auto others = table.find(e.topic);
      if (others == table.end() || e.matched >= others->second) continue;
      unmatched.push_back(s.service + ": " + (e.writer ? "writer" : "reader") + " of " + e.topic + " matched " +
                          std::to_string(e.matched) + " of " + std::to_string(others->second));
    }
  }
  return unmatched;
}

ServiceLinkWatch::ServiceLinkWatch(bus::Participant& participant)
    : subscriber_(participant, bus::topics::kStatus, [this](const msg::ServiceStatus& status) {
        std::lock_guard lock(mutex_);
        latest_[status.service] = status;
      }) {}

std::vector<std::string> ServiceLinkWatch::Unmatched(const std::vector<std::string>& services,
                                                     const std::vector<std::string>& written) const {
  std::vector<std::string> missing;
  std::vector<msg::ServiceStatus> latest;
  {
    std::lock_guard lock(mutex_);
    for (const std::string& service : services)
      if (latest_.count(service) == 0) missing.push_back("no heartbeat from " + service + " yet");
    for (const auto& [name, status] : latest_) latest.push_back(status);
  }
  const std::vector<std::string> links = UnmatchedLinks(latest);
  missing.insert(missing.end(), links.begin(), links.end());
  for (const std::string& topic : written) {
    const bool seen = std::any_of(latest.begin(), latest.end(), [&](const msg::ServiceStatus& s) {
      return std::any_of(s.endpoints.begin(), s.endpoints.end(),
                         [&](const msg::EndpointMatch& e) { return e.writer && e.topic == topic; });
    });
    if (!seen) missing.push_back("no service's heartbeat shows a writer of " + topic);
  }
  return missing;
}

}  // namespace rslam
