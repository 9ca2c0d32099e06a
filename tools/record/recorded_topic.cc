#include "tools/record/recorded_topic.h"

#include <stdexcept>

#include "common/bus/topics.h"
#include "common/bus/typed_cdr.h"

namespace rslam::record {
namespace {

template <class T>
RecordedTopic Entry(const bus::Topic<T>& topic) {
  const bus::MessageTypeInfo* type = bus::FindMessageType(bus::MessageTraits<T>::kTypeName);
  if (type == nullptr) throw std::logic_error(std::string("type not in the registry: ") + bus::MessageTraits<T>::kTypeName);
  return RecordedTopic{std::string(topic.name), type, topic.qos};
}

}  // namespace

const std::vector<RecordedTopic>& TopicTable() {
  // topics.h declares its topics as separate constants (no list to iterate), so they are
  // enumerated here; a topic added there must be added here too (the RecordedTopicTable tests
  // pin that every message type of the registry has a topic).
  namespace t = bus::topics;
  static const std::vector<RecordedTopic> table = {
      Entry(t::kCameraImage),       Entry(t::kOdometryVelocity), Entry(t::kWheelOdometry),
      Entry(t::kTemplatesView),     Entry(t::kPoseCellsAction),  Entry(t::kExperienceMapPose),
      Entry(t::kExperienceMapMap),  Entry(t::kOccupancyProfile), Entry(t::kOccupancyGrid),
      Entry(t::kExplorerCommand),   Entry(t::kExplorerStatus),   Entry(t::kMotionFeedback),
      Entry(t::kGroundTruth),       Entry(t::kSimCamera),        Entry(t::kStatus),
  };
  return table;
}

bus::QosPreset ParsePresetName(std::string_view name) {
  // qos.h has no list of its presets; PresetName answers "?" past the last one.
  std::string known;
  for (int i = 0; i < 64; ++i) {
    const auto preset = static_cast<bus::QosPreset>(i);
    const std::string_view n = bus::PresetName(preset);
    if (n == "?") break;
    if (n == name) return preset;
    known += (known.empty() ? "" : ", ") + std::string(n);
  }
  throw std::invalid_argument("unknown QoS preset '" + std::string(name) + "' (" + known + ")");
}

}  // namespace rslam::record
