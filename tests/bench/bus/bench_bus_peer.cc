#include "tests/bench/bus/bench_bus_peer.h"

#include <sys/prctl.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <exception>
#include <optional>
#include <string_view>

#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"

namespace rslam::bus::bench {
namespace {

using namespace std::chrono_literals;

std::atomic<bool> stop_requested{false};

void RequestStop(int) { stop_requested = true; }

constexpr std::string_view kRoleNames[] = {"echo-small", "echo-image", "sink-images"};

std::optional<PeerRole> ParseRole(std::string_view name) {
  for (std::size_t i = 0; i < std::size(kRoleNames); ++i)
    if (kRoleNames[i] == name) return static_cast<PeerRole>(i);
  return std::nullopt;
}

// Takes from ping and publishes each message on pong, stamped with its arrival time. Taking on
// this thread (rather than in a subscriber callback) lets the echo modify the message it owns
// instead of copying an image; the thread hand-offs are the same as a callback's.
template <class T>
void Echo(Participant& participant, const Topic<T>& ping_topic, const Topic<T>& pong_topic) {
  Publisher<T> pong(participant, pong_topic);
  Subscriber<T> ping(participant, ping_topic);
  while (!stop_requested) {
    std::optional<T> message = ping.TakeOne(100ms);
    if (!message) continue;
    message->header.stamp_ns = SteadyNowNs();
    pong.Publish(*message);
  }
}

void Sink(Participant& participant) {
  Publisher<msg::Velocity> ack(participant, kStreamAck);
  Subscriber<msg::Image> images(participant, kImageStream);
  uint64_t received = 0;
  msg::Velocity reply;
  reply.header.robot_id = participant.robot_id();
  while (!stop_requested) {
    for (const msg::Image& image : images.Take(64)) {
      ++received;
      if ((image.header.frame_seq + 1) % kAckEvery != 0) continue;
      reply.header.frame_seq = image.header.frame_seq;
      reply.header.stamp_ns = static_cast<int64_t>(received);
      ack.Publish(reply);
    }
    images.Wait(100ms);
  }
}

}  // namespace

int64_t SteadyNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::vector<std::string> PeerArguments(PeerRole role, Vendor vendor, int domain_id) {
  return {"--peer", std::string(kRoleNames[static_cast<int>(role)]), VendorName(vendor), std::to_string(domain_id)};
}

bool IsPeerCommandLine(int argc, char** argv) { return argc >= 2 && std::string_view(argv[1]) == "--peer"; }

int RunPeer(int argc, char** argv) {
  // End with the benchmark even if it dies without stopping us.
  const pid_t parent = ::getppid();
  ::prctl(PR_SET_PDEATHSIG, SIGTERM);
  if (::getppid() != parent) return 1;
  struct sigaction action {};
  action.sa_handler = RequestStop;
  ::sigaction(SIGTERM, &action, nullptr);
  ::sigaction(SIGINT, &action, nullptr);

  const std::optional<PeerRole> role = argc == 5 ? ParseRole(argv[2]) : std::nullopt;
  if (!role) {
    std::fprintf(stderr, "usage: %s --peer echo-small|echo-image|sink-images cyclone|fastdds DOMAIN\n", argv[0]);
    return 2;
  }
  try {
    BusConfig config;
    config.dds = argv[3];
    config.domain_id = std::stoi(argv[4]);
    const std::unique_ptr<Participant> participant = Participant::Create(config);
    switch (*role) {
      case PeerRole::kEchoSmall: Echo(*participant, kPingSmall, kPongSmall); break;
      case PeerRole::kEchoImage: Echo(*participant, kPingImage, kPongImage); break;
      case PeerRole::kSinkImages: Sink(*participant); break;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_bus peer: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace rslam::bus::bench
