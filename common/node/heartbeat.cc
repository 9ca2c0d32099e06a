#include "common/node/heartbeat.h"

#include <unistd.h>

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
  publisher_.Publish(s);
}

}  // namespace rslam
