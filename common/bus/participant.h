#pragma once
// The vendor-neutral core of the bus: a process's membership of a DDS domain, and writers and
// readers of serialized CDR. Cyclone DDS and Fast DDS implement it (cyclone_participant.cc,
// fastdds_participant.cc); no other file of the project includes a vendor header. Typed
// Publisher<T> / Subscriber<T> (publisher.h, subscriber.h) and the recorder sit on top.
//
// Robot scoping: a writer publishes in the partition named by its robot id; a reader listens to
// one robot's partition or to "*" (every robot). Messages are keyed by header.robot_id, so a
// state topic keeps the latest sample of each robot.

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "common/bus/bus_config.h"
#include "common/bus/cdr.h"
#include "common/bus/qos.h"

namespace rslam::bus {

class BusError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Writes the key of a serialized message (big-endian CDR of its @key fields) into the key
// writer; throws CdrError on a malformed message.
using KeyReader = void (*)(std::span<const uint8_t> cdr, CdrKeyWriter& key);

// One message type's typed operations, type-erased (typed_cdr.h: CodecFor<T>()). A vendor given a
// codec may decode a received message straight from its receive buffers (one pass over a large
// message fewer than joining the fragments, then decoding).
struct MessageCodec {
  void* (*decode)(CdrReader& reader);                          // a new T; throws CdrError
  void (*encode)(const void* message, std::vector<uint8_t>& out);  // appends CDR
  void* (*copy)(const void* message);                          // a new T
  void (*destroy)(void* message);
};

// A decoded message of the codec's type (owned; move-only).
class DecodedMessage {
 public:
  DecodedMessage() = default;
  DecodedMessage(void* message, const MessageCodec* codec) : message_(message), codec_(codec) {}
  DecodedMessage(DecodedMessage&& other) noexcept
      : message_(std::exchange(other.message_, nullptr)), codec_(other.codec_) {}
  DecodedMessage& operator=(DecodedMessage&& other) noexcept {
    if (this != &other) {
      Reset();
      message_ = std::exchange(other.message_, nullptr);
      codec_ = other.codec_;
    }
    return *this;
  }
  DecodedMessage(const DecodedMessage&) = delete;
  DecodedMessage& operator=(const DecodedMessage&) = delete;
  ~DecodedMessage() { Reset(); }

  explicit operator bool() const { return message_ != nullptr; }
  void* get() const { return message_; }
  const MessageCodec* codec() const { return codec_; }
  DecodedMessage Copy() const { return message_ ? DecodedMessage(codec_->copy(message_), codec_) : DecodedMessage(); }
  void Reset() {
    if (message_ != nullptr) codec_->destroy(message_);
    message_ = nullptr;
  }

 private:
  void* message_ = nullptr;
  const MessageCodec* codec_ = nullptr;
};

struct TopicSpec {
  std::string topic;        // e.g. "camera/image"
  std::string type_name;    // e.g. "rslam::msg::Image"
  KeyReader key_reader = nullptr;  // null for an unkeyed type
  QosPreset qos = QosPreset::kStream;
  // Partition: a robot id to publish in or listen to, or "*" to listen to every robot.
  std::string partition;
  // Typed subscribers pass their type's codec: their samples may then arrive decoded
  // (RawSample::message). Readers without one always get bytes.
  const MessageCodec* codec = nullptr;
};

struct RawSample {
  std::vector<uint8_t> cdr;       // with the 4-byte encapsulation header; empty if message is set
  DecodedMessage message;         // only for readers with a codec, when the vendor decoded it
  int64_t source_timestamp_ns = 0;  // DDS source timestamp (write time), not the frame stamp
};

class RawWriter {
 public:
  virtual ~RawWriter() = default;
  // Publishes serialized CDR (with encapsulation header). Throws BusError on failure, including
  // a reliable writer blocked longer than the preset allows.
  virtual void Write(std::span<const uint8_t> cdr) = 0;
  // The same, handing the buffer over (no copy where the vendor can keep it), and a buffer to
  // serialize the next message into (a recycled one where the vendor pools them). Not
  // thread-safe: Publisher serializes its calls.
  virtual void WriteOwned(std::vector<uint8_t>&& cdr) {
    Write(cdr);
    spare_ = std::move(cdr);
  }
  virtual std::vector<uint8_t> AcquireBuffer() { return std::move(spare_); }
  virtual int MatchedReaders() const = 0;
  // Waits until every matched reliable reader acknowledged everything written.
  virtual bool WaitForAcknowledgments(std::chrono::milliseconds timeout) = 0;

 private:
  std::vector<uint8_t> spare_;
};

class RawReader {
 public:
  virtual ~RawReader() = default;
  // Waits until data may be available (true) or the timeout passes / Interrupt() is called.
  virtual bool Wait(std::chrono::milliseconds timeout) = 0;
  // Moves up to max samples into out (appending); returns how many.
  virtual std::size_t Take(std::vector<RawSample>& out, std::size_t max) = 0;
  virtual int MatchedWriters() const = 0;
  // Wakes a thread blocked in Wait.
  virtual void Interrupt() = 0;
};

// A typed reader or writer of a participant and how many remote endpoints it has matched.
struct EndpointMatchCount {
  std::string topic;
  bool writer = false;
  int matched = 0;
};

class Participant {
 public:
  // Joins config.domain_id with config.vendor(). Throws BusError (or ConfigError) naming what
  // failed.
  static std::unique_ptr<Participant> Create(const BusConfig& config);

  virtual ~Participant() = default;
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  virtual std::unique_ptr<RawWriter> CreateRawWriter(const TopicSpec& spec) = 0;
  virtual std::unique_ptr<RawReader> CreateRawReader(const TopicSpec& spec) = 0;

  // Publisher<T> and Subscriber<T> register their endpoint for as long as they live, so that
  // Matches() (the heartbeat's endpoint list) can say how far discovery has got.
  void Track(const std::string& topic, const RawWriter* writer);
  void Track(const std::string& topic, const RawReader* reader);
  void Untrack(const void* endpoint);
  std::vector<EndpointMatchCount> Matches() const;

  const BusConfig& config() const { return config_; }
  Vendor vendor() const { return config_.vendor(); }
  const std::string& robot_id() const { return config_.robot_id; }

 protected:
  explicit Participant(BusConfig config) : config_(std::move(config)) {}

 private:
  const BusConfig config_;
  struct Tracked {
    std::string topic;
    const RawWriter* writer = nullptr;
    const RawReader* reader = nullptr;
  };
  mutable std::mutex tracked_mutex_;
  std::vector<Tracked> tracked_;
};

// Vendor back-ends (defined in cyclone_participant.cc and fastdds_participant.cc).
std::unique_ptr<Participant> CreateCycloneParticipant(const BusConfig& config);
std::unique_ptr<Participant> CreateFastDdsParticipant(const BusConfig& config);

// The built-in loopback-only XML configurations (deploy/dds/*-loopback.xml, embedded).
extern const char* const kCycloneLoopbackXml;
extern const char* const kFastDdsLoopbackXml;

}  // namespace rslam::bus
