#pragma once
// Typed (de)serialization of generated message types to and from CDR buffers.

#include <memory>
#include <span>
#include <vector>

#include "common/bus/cdr.h"
#include "common/bus/message_traits.h"
#include "common/bus/participant.h"

namespace rslam::bus {

template <Message T>
void AppendCdr(const T& msg, std::vector<uint8_t>& out) {
  CdrWriter writer(out);
  Serialize(writer, msg);
  writer.Finish();
}

template <Message T>
std::vector<uint8_t> ToCdr(const T& msg) {
  std::vector<uint8_t> out;
  AppendCdr(msg, out);
  return out;
}

// Throws CdrError if the bytes are not a well-formed T.
template <Message T>
T FromCdr(std::span<const uint8_t> cdr) {
  CdrReader reader(cdr);
  T msg;
  Deserialize(reader, msg);
  return msg;
}

template <Message T>
void ReadKey(std::span<const uint8_t> cdr, CdrKeyWriter& key) {
  CdrReader reader(cdr);
  ReadKeyFields(reader, key, static_cast<T*>(nullptr));
}

template <Message T>
const MessageCodec* CodecFor() {
  static constexpr MessageCodec kCodec{
      .decode = [](CdrReader& reader) -> void* {
        auto msg = std::make_unique<T>();
        Deserialize(reader, *msg);
        return msg.release();
      },
      .encode = [](const void* msg, std::vector<uint8_t>& out) { AppendCdr(*static_cast<const T*>(msg), out); },
      .copy = [](const void* msg) -> void* { return new T(*static_cast<const T*>(msg)); },
      .destroy = [](void* msg) { delete static_cast<T*>(msg); },
  };
  return &kCodec;
}

template <Message T>
constexpr KeyReader KeyReaderFor() {
  return MessageTraits<T>::kKeyed ? &ReadKey<T> : nullptr;
}

}  // namespace rslam::bus
