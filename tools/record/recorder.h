#pragma once
// `rslam record`'s transport side: subscribes raw to the topics of the topic table and hands
// every message, still serialized, to a RecordingWriter (MCAP). Messages are never decoded; only
// the robot id (the first field of every message's header) is read from the CDR when a reader
// listens to every robot, because DDS does not tell which partition a sample came from.
//
// Threads: one reader thread per (topic, partition) takes samples from DDS and stamps their
// receive time; one writer thread serializes them into the file (compression included), so DDS
// threads never wait for the disk. Between them a bounded queue (MessageQueue) counts what it
// cannot hold as dropped.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "common/bus/participant.h"
#include "tools/record/message_queue.h"
#include "tools/record/recorded_topic.h"
#include "tools/record/recording_writer.h"

namespace rslam::record {

struct RecorderOptions {
  RecordingFileOptions file;
  // ECMAScript regular expressions searched in the DDS topic name ("" = no filter).
  std::string topics_regex;
  std::string exclude_regex;
  // Robots to record (one partition each); empty = every robot ("*").
  std::vector<std::string> robots;
  // Messages taken from DDS but not yet written may hold at most this many bytes.
  std::size_t queue_bytes = std::size_t{1} << 30;
  // The open chunk is handed to the OS at least this often, so a killed recorder loses little.
  std::chrono::milliseconds flush_period{1000};
};

// One subscription of the recorder.
struct RecorderSubscription {
  std::string topic;
  std::string partition;   // a robot id or "*"
  int matched_writers = 0;
};

struct RecorderStats {
  uint64_t received = 0;      // taken from DDS
  uint64_t written = 0;       // in the file
  uint64_t dropped = 0;       // refused by the full queue
  uint64_t unattributed = 0;  // no readable robot id in the header (malformed), not recorded
  std::size_t channels = 0;
  std::size_t queue_peak_bytes = 0;
};

class Recorder {
 public:
  // Creates the file and the subscriptions and starts recording. Throws std::invalid_argument
  // for bad options (regex, compression, no topic selected), std::runtime_error when the file
  // cannot be created, bus::BusError when DDS refuses a reader.
  Recorder(bus::Participant& participant, const RecorderOptions& options);
  // Stops (see Stop) if still running, then deletes the readers.
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Takes what DDS already delivered, writes everything queued and finishes the file(s); the
  // readers are left to the destructor. Rethrows a write error of the writer thread. Idempotent.
  void Stop();

  // The topics selected by the options, in topic-table order.
  const std::vector<RecordedTopic>& topics() const { return topics_; }
  std::vector<RecorderSubscription> Subscriptions() const;
  RecorderStats Stats() const;
  // Non-null once the writer thread failed (disk full, ...); Stop() rethrows it.
  std::exception_ptr error() const;
  // The files written (more than one when splitting).
  std::vector<std::string> paths() const;

 private:
  struct Subscription {
    std::size_t topic_index;
    std::string partition;
    std::unique_ptr<bus::RawReader> reader;
    std::thread thread;
  };
  void ReadLoop(Subscription& subscription);
  void TakeAvailable(Subscription& subscription, std::vector<bus::RawSample>& batch);
  void WriteLoop();

  const RecorderOptions options_;
  std::vector<RecordedTopic> topics_;
  std::unique_ptr<RecordingWriter> writer_;
  MessageQueue queue_;
  std::vector<std::unique_ptr<Subscription>> subscriptions_;
  std::thread writer_thread_;

  std::atomic<bool> stop_readers_{false};
  std::atomic<bool> stop_writer_{false};
  bool stopped_ = false;
  std::atomic<uint64_t> received_{0};
  std::atomic<uint64_t> written_{0};
  std::atomic<uint64_t> unattributed_{0};
  std::atomic<std::size_t> channels_{0};
  mutable std::mutex error_mutex_;
  std::exception_ptr error_;
};

// The robot id of a serialized rslam message: the first field of its header, read without
// decoding the rest. Throws bus::CdrError when the bytes do not start with a valid string.
std::string RobotIdOf(std::span<const uint8_t> cdr);

}  // namespace rslam::record
