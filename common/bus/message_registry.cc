#include "common/bus/message_registry.h"

#include "common/bus/typed_cdr.h"
#include "rslam/msg/all_messages.h"

namespace rslam::bus {
namespace {

template <class T>
std::vector<uint8_t> WithRobotId(std::span<const uint8_t> cdr, const std::string& robot_id) {
  T msg = FromCdr<T>(cdr);
  msg.header.robot_id = robot_id;
  return ToCdr(msg);
}

template <class T>
void Validate(std::span<const uint8_t> cdr) {
  FromCdr<T>(cdr);
}

#define RSLAM_REGISTRY_ENTRY(Type)                                                                \
  MessageTypeInfo{MessageTraits<msg::Type>::kTypeName, MessageTraits<msg::Type>::kIdl,            \
                  KeyReaderFor<msg::Type>(), &WithRobotId<msg::Type>, &Validate<msg::Type>},

const MessageTypeInfo kTypes[] = {RSLAM_FOR_EACH_MESSAGE(RSLAM_REGISTRY_ENTRY)};

}  // namespace

std::span<const MessageTypeInfo> AllMessageTypes() { return kTypes; }

const MessageTypeInfo* FindMessageType(std::string_view type_name) {
  for (const auto& t : kTypes)
    if (type_name == t.type_name) return &t;
  return nullptr;
}

}  // namespace rslam::bus
