// The recorder's copy of the topic table stays complete: every message type of the registry is
// carried by at least one topic, names are unique, and every preset name parses back.
#include <gtest/gtest.h>

#include <set>

#include "common/bus/message_registry.h"
#include "tools/record/recorded_topic.h"

namespace rslam::record {
namespace {

TEST(RecordedTopicTable, EveryMessageTypeHasATopicAndNamesAreUnique) {
  std::set<std::string> names;
  std::set<std::string> types;
  for (const auto& t : TopicTable()) {
    ASSERT_NE(t.type, nullptr) << t.name;
    EXPECT_TRUE(names.insert(t.name).second) << "duplicate topic " << t.name;
    types.insert(t.type->type_name);
  }
  for (const auto& type : bus::AllMessageTypes())
    EXPECT_TRUE(types.count(type.type_name)) << type.type_name << " has no topic in tools/record/recorded_topic.cc";
}

TEST(RecordedTopicTable, PresetNamesParseBack) {
  for (const auto& t : TopicTable()) EXPECT_EQ(bus::ParseQosPreset(bus::PresetName(t.qos)), t.qos) << t.name;
  EXPECT_THROW(bus::ParseQosPreset("fast"), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::record
