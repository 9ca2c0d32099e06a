#pragma once
// Every message type of idl/, looked up by DDS type name: what the recorder and player need to
// handle a topic without knowing its C++ type.

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/bus/participant.h"

namespace rslam::bus {

struct MessageTypeInfo {
  const char* type_name;  // "rslam::msg::Image"
  const char* idl;        // self-contained IDL text (the MCAP schema, encoding omgidl)
  KeyReader key_reader;   // null for unkeyed types
  // Re-serializes a message with header.robot_id replaced (for --robot-remap).
  std::vector<uint8_t> (*with_robot_id)(std::span<const uint8_t> cdr, const std::string& robot_id);
  // Parses the whole message; throws CdrError if it is malformed.
  void (*validate)(std::span<const uint8_t> cdr);
};

std::span<const MessageTypeInfo> AllMessageTypes();
// Null when no type of that name exists.
const MessageTypeInfo* FindMessageType(std::string_view type_name);

// Whether two IDL texts define the same messages: their tokens agree once comments and layout are
// set aside (a recording made by a build that only reworded a comment still reads).
bool SameIdlDefinition(std::string_view a, std::string_view b);

}  // namespace rslam::bus
