#include "common/bus/message_registry.h"

#include <cctype>

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

namespace {

// The IDL's tokens without comments or layout.
std::vector<std::string> IdlTokens(std::string_view idl) {
  std::vector<std::string> tokens;
  auto word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  for (size_t i = 0; i < idl.size();) {
    if (std::isspace(static_cast<unsigned char>(idl[i]))) {
      ++i;
    } else if (idl.compare(i, 2, "//") == 0) {
      i = idl.find('\n', i);
    } else if (idl.compare(i, 2, "/*") == 0) {
      const size_t end = idl.find("*/", i + 2);
      i = end == std::string_view::npos ? end : end + 2;
    } else if (word(idl[i])) {
      const size_t start = i;
      while (i < idl.size() && word(idl[i])) ++i;
      tokens.emplace_back(idl.substr(start, i - start));
    } else {
      tokens.emplace_back(1, idl[i++]);
    }
  }
  return tokens;
}

}  // namespace

bool SameIdlDefinition(std::string_view a, std::string_view b) { return IdlTokens(a) == IdlTokens(b); }

}  // namespace rslam::bus
