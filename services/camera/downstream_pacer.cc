#include "services/camera/downstream_pacer.h"

#include <stdexcept>
#include <string>

namespace rslam::camera {

DownstreamPacer::DownstreamPacer(int stage_count, int max_frames_in_flight, Clock::duration stage_timeout,
                                 Clock::duration startup_timeout)
    : max_frames_in_flight_(max_frames_in_flight),
      stage_timeout_(stage_timeout),
      startup_timeout_(startup_timeout),
      stages_(static_cast<std::size_t>(stage_count < 0 ? 0 : stage_count)) {
  if (stage_count < 0) throw std::invalid_argument("DownstreamPacer: negative stage count");
  if (max_frames_in_flight < 0) throw std::invalid_argument("DownstreamPacer: negative max_frames_in_flight");
  if (stage_timeout < Clock::duration::zero() || startup_timeout < Clock::duration::zero())
    throw std::invalid_argument("DownstreamPacer: negative timeout");
}

void DownstreamPacer::Start(Clock::time_point now) {
  if (!started_) started_ = now;
}

void DownstreamPacer::Report(int stage, uint64_t frame_seq, Clock::time_point now) {
  if (stage < 0 || stage >= static_cast<int>(stages_.size()))
    throw std::out_of_range("DownstreamPacer: stage " + std::to_string(stage));
  Stage& s = stages_[static_cast<std::size_t>(stage)];
  if (!s.last_seq || frame_seq > *s.last_seq) s.last_seq = frame_seq;
  s.last_report = now;
}

bool DownstreamPacer::MayPublish(uint64_t frame_seq, Clock::time_point now) const {
  if (frame_seq <= static_cast<uint64_t>(max_frames_in_flight_)) return true;
  const uint64_t needed = frame_seq - static_cast<uint64_t>(max_frames_in_flight_);
  for (const Stage& s : stages_) {
    if (s.last_seq) {
      if (*s.last_seq >= needed) continue;
      if (now - s.last_report >= stage_timeout_) continue;  // gone quiet: not waited for
      return false;
    }
    if (started_ && now - *started_ >= startup_timeout_) continue;  // never came
    return false;
  }
  return true;
}

}  // namespace rslam::camera
