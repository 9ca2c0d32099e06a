#include "common/node/frame_pacer.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace rslam {

FramePacer::FramePacer(int stage_count, int max_frames_in_flight, Clock::duration stage_timeout,
                       Clock::duration startup_timeout)
    : max_frames_in_flight_(max_frames_in_flight),
      stage_timeout_(stage_timeout),
      startup_timeout_(startup_timeout),
      stages_(static_cast<size_t>(std::max(stage_count, 0))) {
  if (stage_count < 0) throw std::invalid_argument("FramePacer: negative stage count");
  // With none in flight not even the first frame could go before it was processed.
  if (max_frames_in_flight < 1) throw std::invalid_argument("FramePacer: max_frames_in_flight must be at least 1");
  if (stage_timeout < Clock::duration::zero() || startup_timeout < Clock::duration::zero())
    throw std::invalid_argument("FramePacer: negative timeout");
}

void FramePacer::Start(Clock::time_point now) {
  if (!started_) started_ = now;
}

void FramePacer::Report(int stage, uint64_t frame_seq, Clock::time_point now) {
  if (stage < 0 || stage >= stage_count())
    throw std::out_of_range("FramePacer: stage " + std::to_string(stage) + " out of range");
  Stage& s = stages_[static_cast<size_t>(stage)];
  // A restarted pipeline may report lower numbers again; the latest report is what counts.
  s.last_seq = frame_seq;
  s.last_report = now;
}

bool FramePacer::MayPublish(uint64_t frame_seq, Clock::time_point now) const {
  if (frame_seq < static_cast<uint64_t>(max_frames_in_flight_)) return true;
  const uint64_t needed = frame_seq - static_cast<uint64_t>(max_frames_in_flight_);
  for (const Stage& s : stages_) {
    if (s.last_seq) {
      if (*s.last_seq >= needed) continue;
      if (now - s.last_report >= stage_timeout_) continue;  // silent: gone or stuck
      return false;
    }
    if (started_ && now - *started_ >= startup_timeout_) continue;  // never came up
    return false;
  }
  return true;
}

bool FramePacer::PassingAbsentStage(uint64_t frame_seq, Clock::time_point now) const {
  if (frame_seq < static_cast<uint64_t>(max_frames_in_flight_)) return false;
  const uint64_t needed = frame_seq - static_cast<uint64_t>(max_frames_in_flight_);
  for (const Stage& s : stages_)
    if (!s.last_seq || *s.last_seq < needed) return true;
  return false;
}

std::optional<uint64_t> FramePacer::LastReported(int stage) const {
  if (stage < 0 || stage >= stage_count())
    throw std::out_of_range("FramePacer: stage " + std::to_string(stage) + " out of range");
  return stages_[static_cast<size_t>(stage)].last_seq;
}

}  // namespace rslam
