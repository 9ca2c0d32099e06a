// The launcher's parts without DDS: the process supervisor (restart with backoff, giving up,
// stopping a child that ignores SIGTERM) and launch profiles (the shipped ones load; a bad key
// is named; specs carry the vendor, domain and arguments).
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <string>
#include <thread>

#include "common/config/config_loader.h"
#include "tests/support/child_process.h"
#include "tools/launch/launch_profile.h"
#include "tools/launch/process_supervisor.h"

namespace rslam::launch {
namespace {

using namespace std::chrono_literals;

ProcessSpec Shell(const std::string& name, const std::string& script) {
  ProcessSpec spec;
  spec.name = name;
  spec.executable = "/bin/sh";
  spec.args = {"-c", script};
  return spec;
}

ProcessSupervisor::Status StatusOf(const ProcessSupervisor& supervisor, const std::string& name) {
  for (const auto& s : supervisor.Statuses())
    if (s.name == name) return s;
  throw std::runtime_error("no process " + name);
}

TEST(ProcessSupervisorTest, ACrashingProcessIsRestartedWithBackoffThenGivenUp) {
  ProcessSupervisor supervisor(RestartPolicy{.backoff_initial_s = 0.05, .backoff_max_s = 0.2, .max_restarts = 3});
  std::vector<std::string> events;
  supervisor.OnEvent([&](const std::string& e) { events.push_back(e); });
  supervisor.Start(Shell("crasher", "exit 3"));
  const auto start = std::chrono::steady_clock::now();
  ASSERT_TRUE(testing::WaitFor(
      [&] {
        supervisor.Poll();
        return StatusOf(supervisor, "crasher").gave_up;
      },
      10s));
  const auto elapsed = std::chrono::steady_clock::now() - start;
  const auto status = StatusOf(supervisor, "crasher");
  EXPECT_EQ(status.restarts, 3);
  EXPECT_EQ(status.last_exit, "exit 3");
  EXPECT_FALSE(status.running);
  // Backoff 0.05, 0.1, 0.2 s between the restarts.
  EXPECT_GE(elapsed, 350ms);
  EXPECT_NE(events.back().find("gave up after 3 restarts"), std::string::npos) << events.back();
}

TEST(ProcessSupervisorTest, ACleanExitIsNotRestarted) {
  ProcessSupervisor supervisor(RestartPolicy{.backoff_initial_s = 0.01, .backoff_max_s = 0.01, .max_restarts = 3});
  supervisor.Start(Shell("done", "exit 0"));
  ASSERT_TRUE(testing::WaitFor(
      [&] {
        supervisor.Poll();
        return !StatusOf(supervisor, "done").last_exit.empty();
      },
      10s));
  for (int i = 0; i < 5; ++i) {
    std::this_thread::sleep_for(20ms);  // longer than the backoff: a restart would have happened
    supervisor.Poll();
  }
  EXPECT_EQ(StatusOf(supervisor, "done").restarts, 0);
  EXPECT_EQ(StatusOf(supervisor, "done").last_exit, "exit 0");
}

TEST(ProcessSupervisorTest, StopAllKillsAChildThatIgnoresSigterm) {
  testing::ScratchFolder scratch;
  ProcessSupervisor supervisor;
  ProcessSpec stubborn = Shell("stubborn", "trap '' TERM; echo trapped; while :; do sleep 0.05; done");
  stubborn.log_file = scratch / "stubborn.log";
  supervisor.Start(stubborn);
  supervisor.Start(Shell("polite", "exec sleep 30"));
  // The shell says when its trap is in place.
  ASSERT_TRUE(testing::WaitFor(
      [&] {
        std::ifstream log(stubborn.log_file);
        std::string line;
        return std::getline(log, line) && line == "trapped";
      },
      10s));
  EXPECT_FALSE(supervisor.StopAll(300ms));
  EXPECT_FALSE(StatusOf(supervisor, "stubborn").running);
  EXPECT_FALSE(StatusOf(supervisor, "polite").running);
}

TEST(ProcessSupervisorTest, AMissingBinaryIsRefusedAtStart) {
  ProcessSupervisor supervisor;
  ProcessSpec spec;
  spec.name = "ghost";
  spec.executable = "/nonexistent/rslam-ghost";
  EXPECT_THROW(supervisor.Start(spec), std::runtime_error);
}

TEST(LaunchProfileTest, ShippedProfilesLoad) {
  for (const std::string name : {"robot", "base", "all"}) {
    const LaunchProfile profile = LoadLaunchProfile(name, RSLAM_SOURCE_DIR "/deploy/launch");
    EXPECT_FALSE(profile.processes.empty()) << name;
  }
}

TEST(LaunchProfileTest, UnknownKeysAreNamed) {
  testing::ScratchFolder scratch;
  const std::string path = scratch / "p.yaml";
  std::ofstream(path) << "processes:\n  - name: odometry\n    dds: opendds\n";
  try {
    LoadLaunchProfile(path, "");
    FAIL() << "accepted dds: opendds";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("processes[0].dds"), std::string::npos) << e.what();
  }
  std::ofstream(path) << "restart: {backoff_initial_s: 1, retries: 2}\nprocesses: [{name: odometry}]\n";
  try {
    LoadLaunchProfile(path, "");
    FAIL() << "accepted restart.retries";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("restart.retries"), std::string::npos) << e.what();
  }
}

TEST(LaunchProfileTest, SpecsCarryBinaryVendorDomainAndArguments) {
  LaunchProfile profile;
  profile.processes = {{.name = "pose_cells", .command = {}, .args = {"--set", "a=1"}, .dds = ""},
                       {.name = "experience_map", .command = {}, .args = {}, .dds = "fastdds"},
                       {.name = "recorder", .command = {"rslam", "record", "-o", "x.mcap"}, .args = {}, .dds = ""}};
  LaunchOptions options;
  options.bin_dir = "/opt/rslam/bin";
  options.dds = "cyclone";
  options.domain = 7;
  options.robot = "r2";
  options.state_dir = "/var/lib/rslam";
  const auto specs = BuildProcessSpecs(profile, options);
  ASSERT_EQ(specs.size(), 3u);
  EXPECT_EQ(specs[0].executable, "/opt/rslam/bin/rslam-pose-cells");
  EXPECT_EQ(specs[0].args, (std::vector<std::string>{"--robot", "r2", "--state-dir", "/var/lib/rslam", "--set", "a=1"}));
  EXPECT_EQ(specs[0].env.at("RSLAM_DDS"), "cyclone");
  EXPECT_EQ(specs[0].env.at("RSLAM_DOMAIN"), "7");
  EXPECT_EQ(specs[1].env.at("RSLAM_DDS"), "fastdds");
  EXPECT_EQ(specs[2].executable, "/opt/rslam/bin/rslam");
  EXPECT_EQ(specs[2].args, (std::vector<std::string>{"record", "-o", "x.mcap"}));  // not a service: no service flags
}

}  // namespace
}  // namespace rslam::launch
