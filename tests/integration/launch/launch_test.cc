// `rslam launch` and `rslam status` as processes on the test's own DDS domain: the launcher starts
// a profile's services, restarts one killed with SIGKILL, and stops them all on SIGTERM; the
// heartbeats (and `rslam status`) show each service's endpoints and how far discovery got.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>

#include "common/bus/participant.h"
#include "common/bus/subscriber.h"
#include "common/node/heartbeat.h"
#include "tests/support/child_process.h"
#include "tests/support/test_domain.h"

namespace rslam {
namespace {

using namespace std::chrono_literals;

const std::string kRslam = RSLAM_BINARY_DIR "/bin/rslam";

bool ProcessExists(pid_t pid) { return ::kill(pid, 0) == 0; }

bool Matched(const msg::ServiceStatus& status, const std::string& topic, bool writer) {
  for (const msg::EndpointMatch& e : status.endpoints)
    if (e.topic == topic && e.writer == writer) return e.matched > 0;
  return false;
}

class LaunchTest : public ::testing::Test {
 protected:
  LaunchTest() {
    bus::BusConfig config;
    config.domain_id = domain_.id();
    participant_ = bus::Participant::Create(config);
    status_ = std::make_unique<bus::Subscriber<msg::ServiceStatus>>(
        *participant_, bus::topics::kStatus, [this](const msg::ServiceStatus& s) {
          std::lock_guard lock(mutex_);
          latest_[s.service] = s;
        });
  }

  // A profile of the two back-end services with quick heartbeats and restarts.
  std::string WriteProfile() {
    const std::string path = scratch_ / "profile.yaml";
    std::ofstream(path) << "restart: {backoff_initial_s: 0.2, backoff_max_s: 1, max_restarts: 3}\n"
                           "processes:\n"
                           "  - name: experience_map\n"
                           "    args: [--set, service.heartbeat_period_s=0.2]\n"
                           "  - name: pose_cells\n"
                           "    args: [--set, service.heartbeat_period_s=0.2]\n";
    return path;
  }

  std::optional<msg::ServiceStatus> Latest(const std::string& service) {
    std::lock_guard lock(mutex_);
    const auto it = latest_.find(service);
    if (it == latest_.end()) return std::nullopt;
    return it->second;
  }

  testing::TestDomain domain_;
  testing::ScratchFolder scratch_{"rslam-launch-test"};
  std::unique_ptr<bus::Participant> participant_;
  std::mutex mutex_;
  std::map<std::string, msg::ServiceStatus> latest_;
  std::unique_ptr<bus::Subscriber<msg::ServiceStatus>> status_;
};

TEST_F(LaunchTest, RestartsAKilledServiceAndStopsEverythingOnSigterm) {
  testing::ChildProcess launch(kRslam, {"launch", WriteProfile(), "--domain", std::to_string(domain_.id()), "--dds",
                                        "cyclone", "--state-dir", scratch_ / "state", "--log-dir", scratch_ / "logs"});
  // Both up, and the heartbeats say the action link between them is matched at both ends.
  ASSERT_TRUE(testing::WaitFor(
      [&] {
        const auto pc = Latest("pose_cells");
        const auto em = Latest("experience_map");
        return pc && em && pc->state == "running" && em->state == "running" &&
               Matched(*pc, "pose_cells/action", true) && Matched(*em, "pose_cells/action", false);
      },
      20s))
      << launch.Tail();
  const pid_t first_pid = static_cast<pid_t>(Latest("pose_cells")->pid);
  const pid_t map_pid = static_cast<pid_t>(Latest("experience_map")->pid);
  // Nothing publishes odometry on this domain: the pose cells' reader of it is unmatched.
  EXPECT_FALSE(Matched(*Latest("pose_cells"), "odometry/velocity", false));
  // What a frame source waiting for the pipeline sees.
  const ServiceLinkWatch links(*participant_);
  EXPECT_TRUE(testing::WaitFor([&] { return links.Unmatched({"pose_cells", "experience_map"}).empty(); }, 10s))
      << ::testing::PrintToString(links.Unmatched({"pose_cells", "experience_map"}));
  EXPECT_EQ(links.Unmatched({"odometry"}), std::vector<std::string>{"no heartbeat from odometry yet"});
  EXPECT_EQ(links.Unmatched({}, {"odometry/velocity"}),
            std::vector<std::string>{"no service's heartbeat shows a writer of odometry/velocity"});

  ASSERT_EQ(::kill(first_pid, SIGKILL), 0);
  ASSERT_TRUE(testing::WaitFor(
      [&] {
        const auto pc = Latest("pose_cells");
        return pc && pc->state == "running" && static_cast<pid_t>(pc->pid) != first_pid;
      },
      20s))
      << "the launcher did not restart the killed pose cells\n"
      << launch.Tail();
  EXPECT_NE(launch.Output().find("restarted pose_cells"), std::string::npos) << launch.Tail();

  // `rslam status --json` lists both services with their endpoints.
  testing::ChildProcess status(kRslam, {"status", "--domain", std::to_string(domain_.id()), "--dds", "cyclone", "--wait",
                                        "1", "--json"});
  ASSERT_EQ(status.WaitExit(20s), 0) << status.Tail();
  const std::string out = status.Output();
  const auto json = nlohmann::json::parse(out.substr(out.find('[')), nullptr, false);
  ASSERT_FALSE(json.is_discarded()) << out;
  std::map<std::string, nlohmann::json> by_service;
  for (const auto& s : json) by_service[s.at("service").get<std::string>()] = s;
  ASSERT_EQ(by_service.count("pose_cells"), 1u) << out;
  ASSERT_EQ(by_service.count("experience_map"), 1u) << out;
  bool action_reader_matched = false;
  for (const auto& e : by_service["experience_map"].at("endpoints"))
    if (e.at("topic") == "pose_cells/action" && e.at("writer") == false) action_reader_matched = e.at("matched") > 0;
  EXPECT_TRUE(action_reader_matched) << out;

  launch.Signal(SIGTERM);
  ASSERT_EQ(launch.WaitExit(20s), 0) << launch.Tail();
  const pid_t second_pid = static_cast<pid_t>(Latest("pose_cells")->pid);
  EXPECT_FALSE(ProcessExists(second_pid));
  EXPECT_FALSE(ProcessExists(map_pid));
}

TEST_F(LaunchTest, BadProfileKeyIsNamedAndExitsTwo) {
  const std::string path = scratch_ / "bad.yaml";
  std::ofstream(path) << "processes:\n  - name: odometry\n    argz: [--fresh]\n";
  testing::ChildProcess launch(kRslam, {"launch", path, "--domain", std::to_string(domain_.id())});
  EXPECT_EQ(launch.WaitExit(20s), 2);
  EXPECT_NE(launch.Output().find("processes[0].argz"), std::string::npos) << launch.Output();
}

TEST_F(LaunchTest, StatusWithABadConfigKeyNamesItAndExitsTwo) {
  const std::string path = scratch_ / "bad-bus.yaml";
  std::ofstream(path) << "bus:\n  domian_id: 3\n";
  testing::ChildProcess status(kRslam, {"status", "--config", path, "--domain", std::to_string(domain_.id())});
  EXPECT_EQ(status.WaitExit(20s), 2);
  EXPECT_NE(status.Output().find("bus.domian_id"), std::string::npos) << status.Output();
}

}  // namespace
}  // namespace rslam
