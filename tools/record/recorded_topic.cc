#include "tools/record/recorded_topic.h"

#include <stdexcept>

#include "common/bus/topics.h"
#include "common/bus/typed_cdr.h"

namespace rslam::record {
const std::vector<RecordedTopic>& TopicTable() {
  static const std::vector<RecordedTopic> table = [] {
    std::vector<RecordedTopic> out;
    for (const bus::TopicInfo& t : bus::topics::kAll) {
      const bus::MessageTypeInfo* type = bus::FindMessageType(t.type_name);
      if (type == nullptr) throw std::logic_error("type not in the registry: " + std::string(t.type_name));
      out.push_back(RecordedTopic{std::string(t.name), type, t.qos});
    }
    return out;
  }();
  return table;
}

}  // namespace rslam::record
