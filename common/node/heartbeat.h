#pragma once
// Publishes the service's rslam/status heartbeat (state QoS: `rslam status` and the launcher
// see every live service at once).

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"
#include "common/node/service_context.h"

namespace rslam {

class Heartbeat {
 public:
  explicit Heartbeat(ServiceContext& context);
  // Publishes one status message now; `state` is "running" or "stopping".
  void Publish(const std::string& state);

 private:
  ServiceContext& context_;
  bus::Publisher<msg::ServiceStatus> publisher_;
  const std::chrono::steady_clock::time_point start_;
};

// The links among `services` (their latest heartbeats) that discovery has not matched at both
// ends yet: for each topic one of them writes and one reads, a writer that has matched fewer
// readers than there are reading services, or a reader that has matched fewer writers than there
// are writing services, as "odometry: writer of odometry/velocity matched 0 of 1". Empty means a
// sample written now reaches every one of them that reads it (a stream sample written before its
// reader matched never does): start the source of a chain once this is empty.
std::vector<std::string> UnmatchedLinks(const std::vector<msg::ServiceStatus>& services);

// The latest heartbeat of each of this robot's services and what they show unmatched. Frame
// sources (the simulator; the camera on a recorded source) hold their first frame until
// Unmatched() is empty. Only services whose heartbeat has arrived count, so name the services
// expected (a launcher knows them) and the topics that must be written (lockstep topics).
class ServiceLinkWatch {
 public:
  explicit ServiceLinkWatch(bus::Participant& participant);
  // "no heartbeat from S yet" for each of `services` not heard from, UnmatchedLinks over the
  // latest heartbeats, and "no service's heartbeat shows a writer of T" for each of `written`.
  std::vector<std::string> Unmatched(const std::vector<std::string>& services,
                                     const std::vector<std::string>& written = {}) const;

 private:
  mutable std::mutex mutex_;
  std::map<std::string, msg::ServiceStatus> latest_;  // by service name
  bus::Subscriber<msg::ServiceStatus> subscriber_;    // last: its callback uses the members above
};

}  // namespace rslam
