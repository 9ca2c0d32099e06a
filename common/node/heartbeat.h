#pragma once
// Publishes the service's rslam/status heartbeat (state QoS: `rslam status` and the launcher
// see every live service at once).

#include <memory>
#include <string>
#include <vector>

#include "common/bus/publisher.h"
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

}  // namespace rslam
