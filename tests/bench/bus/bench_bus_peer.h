#pragma once
// The far end of bench_bus: a second process (bench_bus itself, started with --peer) that echoes
// pings or swallows an image stream, so that every figure crosses a process boundary over
// loopback UDP, as between two services and as in Cyclone's ddsperf ping/pong. (Within one
// process both vendors skip the network: Cyclone delivers to local readers directly and Fast DDS
// uses its intra-process path, so in-process figures are not the vendor's network path.)
//
// Clock: both processes read std::chrono::steady_clock (CLOCK_MONOTONIC, one clock for the whole
// host), so one-way times are measured directly, not halved from a round trip.

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "common/bus/participant.h"
#include "common/bus/topics.h"

namespace rslam::bus::bench {

// Ping/pong topics use the presets of the project's topics they stand for: a small message as
// odometry/velocity (stream), an image as camera/image (sensor).
inline constexpr Topic<msg::Velocity> kPingSmall{"bench/ping_small", topics::kOdometryVelocity.qos};
inline constexpr Topic<msg::Velocity> kPongSmall{"bench/pong_small", topics::kOdometryVelocity.qos};
inline constexpr Topic<msg::Image> kPingImage{"bench/ping_image", topics::kCameraImage.qos};
inline constexpr Topic<msg::Image> kPongImage{"bench/pong_image", topics::kCameraImage.qos};
// Lossless image stream (reliable keep-all: the writer blocks while the reader lags) and the
// sink's acknowledgments: header.frame_seq = the image's frame_seq, header.stamp_ns = images
// received so far. The sink acknowledges every image whose (frame_seq + 1) % kAckEvery == 0.
inline constexpr Topic<msg::Image> kImageStream{"bench/image_stream", QosPreset::kStream};
inline constexpr Topic<msg::Velocity> kStreamAck{"bench/image_stream_ack", QosPreset::kStream};
inline constexpr uint64_t kAckEvery = 50;

enum class PeerRole {
  kEchoSmall,   // takes kPingSmall, publishes it on kPongSmall with header.stamp_ns = its arrival time
  kEchoImage,   // the same for kPingImage / kPongImage
  kSinkImages,  // takes kImageStream, acknowledges on kStreamAck
};

int64_t SteadyNowNs();

// Command-line arguments that make bench_bus run as a peer (after the program name).
std::vector<std::string> PeerArguments(PeerRole role, Vendor vendor, int domain_id);

// True if argv asks for peer mode (argv[1] == "--peer").
bool IsPeerCommandLine(int argc, char** argv);

// Runs the peer until SIGTERM or SIGINT (or the parent's death); returns the exit code (2 on
// bad arguments, 1 on a bus error, reported on stderr).
int RunPeer(int argc, char** argv);

}  // namespace rslam::bus::bench
