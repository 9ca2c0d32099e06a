#pragma once
// The topics `rslam record` subscribes to: every entry of the topic table (common/bus/topics.h)
// with its message type from the registry (message_registry.h) and its QoS preset.

#include <string>
#include <string_view>
#include <vector>

#include "common/bus/message_registry.h"
#include "common/bus/qos.h"

namespace rslam::record {

struct RecordedTopic {
  std::string name;                      // DDS topic name, e.g. "camera/image"
  const bus::MessageTypeInfo* type;      // never null
  bus::QosPreset qos;                    // the preset publishers use (stored as channel metadata)
};

// Every topic of the topic table, in table order.
const std::vector<RecordedTopic>& TopicTable();


}  // namespace rslam::record
