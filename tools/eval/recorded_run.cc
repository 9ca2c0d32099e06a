#include "tools/eval/recorded_run.h"

#include <map>
#include <set>
#include <span>
#include <stdexcept>

#include "common/bus/message_registry.h"
#include "common/bus/topics.h"
#include "common/bus/typed_cdr.h"
#include "common/mcap/mcap_reader.h"

namespace rslam::eval {

namespace {

// The recorder names a channel /<robot>/<topic>.
bool IsTopic(const std::string& channel, std::string_view topic) {
  return channel.size() > topic.size() && channel.ends_with(topic) && channel[channel.size() - topic.size() - 1] == '/';
}

template <class T>
T Decode(const mcap::MessageView& m, std::string_view topic) {
  const std::span<const uint8_t> cdr(reinterpret_cast<const uint8_t*>(m.data.data()), m.data.size());
  try {
    return bus::FromCdr<T>(cdr);
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string(topic) + " message at log time " + std::to_string(m.log_time) +
                                " does not decode: " + e.what());
  }
}

}  // namespace

RecordedRun ReadRecordedRun(const std::string& path, const std::string& robot) {
  namespace t = bus::topics;
  RecordedRun run;
  run.robot = robot;
  std::map<uint64_t, RecordedFrame> frames;
  // The frame of `header` if it is the robot's (the first robot read when none was named).
  const auto frame_of = [&](const msg::Header& header) -> RecordedFrame* {
    if (run.robot.empty()) run.robot = header.robot_id;
    if (header.robot_id != run.robot) return nullptr;
    auto [it, inserted] = frames.try_emplace(header.frame_seq);
    if (inserted) {
      it->second.frame_seq = header.frame_seq;
      it->second.stamp_ns = header.stamp_ns;
    }
    return &it->second;
  };
  const mcap::McapReader reader(path);
  // A channel recorded by a build whose message differs from today's is left out (it would not
  // decode): a recording made before pose_cells/action carried the floor boundary still replays.
  std::set<uint16_t> other_definition;
  for (const auto& [id, channel] : reader.channels()) {
    const auto schema = reader.schemas().find(channel.schema_id);
    if (schema == reader.schemas().end()) continue;
    const bus::MessageTypeInfo* type = bus::FindMessageType(schema->second.name);
    if (type != nullptr && !bus::SameIdlDefinition(schema->second.data, type->idl)) {
      other_definition.insert(id);
      run.skipped.push_back(channel.topic + ": recorded with another definition of " + schema->second.name);
    }
  }
  reader.ForEachMessage({}, [&](const mcap::MessageView& m) {
    if (other_definition.count(m.channel->id)) return;
    const std::string& channel = m.channel->topic;
    if (IsTopic(channel, t::kGroundTruth.name)) {
      const auto v = Decode<msg::GroundTruthPose>(m, t::kGroundTruth.name);
      if (RecordedFrame* f = frame_of(v.header)) {
        f->truth = Pose2D{v.x_m, v.y_m, v.theta_rad};
        f->stamp_ns = v.header.stamp_ns;  // the simulator's stamp of the frame
      }
    } else if (IsTopic(channel, t::kOdometryVelocity.name)) {
      auto v = Decode<msg::Velocity>(m, t::kOdometryVelocity.name);
      if (RecordedFrame* f = frame_of(v.header)) f->velocity = std::move(v);
    } else if (IsTopic(channel, t::kTemplatesView.name)) {
      auto v = Decode<msg::ViewTemplate>(m, t::kTemplatesView.name);
      if (RecordedFrame* f = frame_of(v.header)) f->view = std::move(v);
    } else if (IsTopic(channel, t::kPoseCellsAction.name)) {
      auto v = Decode<msg::PoseCellAction>(m, t::kPoseCellsAction.name);
      if (RecordedFrame* f = frame_of(v.header)) f->action = std::move(v);
    } else if (IsTopic(channel, t::kOccupancyProfile.name)) {
      auto v = Decode<msg::ObstacleProfile>(m, t::kOccupancyProfile.name);
      if (RecordedFrame* f = frame_of(v.header)) f->profile = std::move(v);
    }
  });
  run.frames.reserve(frames.size());
  for (auto& [seq, frame] : frames) run.frames.push_back(std::move(frame));
  return run;
}

}  // namespace rslam::eval
