#pragma once
// `rslam play`'s engine: republishes recorded MCAP channels on the bus, each with its recorded
// QoS preset, in its recorded robot's partition (or a remapped one), with the recorded timing
// scaled by a rate, or as fast as reliable readers take the messages.
//
// PlayFile is also the hook for system tests: record a pipeline run, then replay it into fresh
// services with the same call the command line uses.

#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <stop_token>
#include <string>
#include <vector>

#include "common/bus/participant.h"

namespace rslam::record {

struct PlayOptions {
  // Playback speed: 2 = twice as fast as recorded. Ignored when max_speed.
  double rate = 1.0;
  // As fast as reliable readers take the messages, losing none: keep-all channels rely on
  // back-pressure; shallow keep-last channels (sensor, state) wait for every matched reader's
  // acknowledgment of each message, deep ones (log) of every quarter of their depth.
  bool max_speed = false;
  // Play again from the start until stopped.
  bool loop = false;
  // Window in seconds from the recording's first message (log time).
  double start_s = 0.0;
  double end_s = std::numeric_limits<double>::infinity();
  // ECMAScript regular expression searched in the DDS topic name ("" = every topic).
  std::string topics_regex;
  // Recorded robot id -> robot id to publish as (partition and header.robot_id).
  std::map<std::string, std::string> robot_remap;
  // Before the first message: wait until every channel's writer has at least this many matched
  // readers (0 = do not wait), for at most wait_timeout, then settle.
  int wait_for_readers = 1;
  std::chrono::milliseconds wait_timeout{5000};
  // A writer sees a reader match a little before the reader has matched the writer; a volatile
  // reader misses what is written in between. This pause after matching covers that gap.
  std::chrono::milliseconds settle{300};
  // How long to wait for acknowledgments (per message at max speed, and at the end).
  std::chrono::milliseconds ack_timeout{10000};
  // Progress and warnings for a command line (the library itself prints nothing).
  std::function<void(const std::string&)> on_event;
};

struct PlayedChannel {
  std::string dds_topic;
  std::string type_name;
  std::string qos;
  std::string recorded_robot;
  std::string partition;  // the robot it was published as
  uint64_t messages = 0;  // published (over every loop)
};

struct PlayReport {
  uint64_t messages = 0;          // published
  uint64_t loops = 0;             // complete passes over the recording
  bool readers_matched = true;    // every channel reached wait_for_readers in time
  bool stopped = false;           // interrupted by the stop token
  uint64_t ack_timeouts = 0;      // max speed: messages some reader did not acknowledge in time
  uint64_t malformed = 0;         // could not be re-serialized for a robot remap; skipped
  std::vector<PlayedChannel> channels;
  std::vector<std::string> skipped_channels;  // not playable (unknown type, encoding), with why
};

// Plays one recording. Every file is validated before anything is published (McapError).
// Throws std::invalid_argument for bad options, bus::BusError when a write fails (e.g. a
// keep-all reader blocked the writer beyond its limit).
PlayReport PlayFile(bus::Participant& participant, const std::string& path, const PlayOptions& options,
                    std::stop_token stop = {});
// Plays the files of a split recording (or several recordings) one after the other, with one
// timeline: times are taken from the files' log times, the first message of the first file = 0 s.
PlayReport PlayFiles(bus::Participant& participant, const std::vector<std::string>& paths,
                     const PlayOptions& options, std::stop_token stop = {});

// Parses "A=B" into {A, B}; throws std::invalid_argument naming the bad text.
std::pair<std::string, std::string> ParseRobotRemap(const std::string& text);

}  // namespace rslam::record
