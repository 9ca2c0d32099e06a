#pragma once
// Publishes the service's rslam/status heartbeat (state QoS: `rslam status` and the launcher
// see every live service at once).

#include <memory>
#include <string>

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

}  // namespace rslam
