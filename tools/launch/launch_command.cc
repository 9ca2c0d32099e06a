#include "tools/launch/launch_command.h"

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>

#include "common/bus/subscriber.h"
#include "common/config/config_loader.h"
#include "common/node/heartbeat.h"
#include "common/node/service_context.h"
#include "common/node/shutdown_signal.h"
#include "tools/launch/launch_profile.h"
#include "tools/launch/process_supervisor.h"

namespace rslam::launch {
namespace fs = std::filesystem;

std::string ExecutableDir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(".") : exe.parent_path().string();
}

std::string DeployDir() {
  if (const char* env = std::getenv("RSLAM_DEPLOY_DIR"); env != nullptr && *env != '\0') return env;
  return RSLAM_SOURCE_DIR "/deploy";
}

void RegisterLaunchCommand(CLI::App& rslam) {
  auto* cmd = rslam.add_subcommand("launch", "start a launch profile's processes, restart crashed ones, stop on Ctrl-C");
  struct Args {
    std::string profile;
    LaunchOptions options;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("profile", args->profile, "profile name in deploy/launch (robot, base, all) or a YAML path")->required();
  cmd->add_option("--robot", args->options.robot, "robot id for every service");
  cmd->add_option("--dds", args->options.dds, "DDS vendor for every process (env RSLAM_DDS)")
      ->check(CLI::IsMember({"cyclone", "fastdds"}));
  cmd->add_option("--domain", args->options.domain, "DDS domain id")->check(CLI::Range(0, 229));
  cmd->add_option("--config", args->options.config, "config file for every service (overrides the profile's)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--log-dir", args->options.log_dir, "write each process's output to DIR/NAME.log");
  cmd->add_option("--state-dir", args->options.state_dir, "state folder for the stateful services");
  cmd->callback([args] {
    args->options.bin_dir = ExecutableDir();
    LaunchProfile profile;
    try {
      profile = LoadLaunchProfile(args->profile, DeployDir() + "/launch");
    } catch (const ConfigError& e) {
      std::cerr << "rslam launch: " << e.what() << std::endl;  // CLI11 exits silently on RuntimeError
      throw CLI::RuntimeError(2);
    }
    if (!args->options.log_dir.empty()) fs::create_directories(args->options.log_dir);
    BlockShutdownSignals();
    ProcessSupervisor supervisor(profile.restart);
    supervisor.OnEvent([](const std::string& e) { std::cerr << "[launch] " << e << std::endl; });
    for (const auto& spec : BuildProcessSpecs(profile, args->options)) supervisor.Start(spec);
    struct Ctx {
      ProcessSupervisor& s;
    } ctx{supervisor};
    WaitForShutdown(std::chrono::milliseconds(100), [](void* a) { static_cast<Ctx*>(a)->s.Poll(); }, &ctx);
    std::cerr << "[launch] stopping" << std::endl;
    if (!supervisor.StopAll()) throw CLI::RuntimeError(1);
  });
}

namespace {

// Bus settings for a diagnostic command: the `bus` section of --config, then the environment,
// then the flags.
struct DiagnosticBusArgs {
  std::string config_file;
  std::string dds;
  int domain = -1;
  std::string robot;

  void AddFlags(CLI::App* cmd) {
    cmd->add_option("--config", config_file, "YAML config whose `bus` section to use (e.g. a deployment's DDS XML)")
        ->check(CLI::ExistingFile);
    cmd->add_option("--dds", dds, "DDS vendor (env RSLAM_DDS)")->check(CLI::IsMember({"cyclone", "fastdds"}));
    cmd->add_option("--domain", domain, "DDS domain id (env RSLAM_DOMAIN)")->check(CLI::Range(0, 229));
  }
  bus::BusConfig Resolve(const std::string& default_robot) const {
    bus::BusConfig config;
    try {
      if (!config_file.empty()) LoadConfigSection(LoadYamlFile(config_file), "bus", config);
      if (robot.empty() && config_file.empty()) config.robot_id = default_robot;
      config.ApplyEnvironment();
      if (!dds.empty()) config.dds = dds;
      if (domain >= 0) config.domain_id = domain;
      if (!robot.empty()) config.robot_id = robot;
      config.Validate();
    } catch (const ConfigError& e) {
      std::cerr << "config error: " << e.what() << std::endl;  // CLI11 exits silently on RuntimeError
      throw CLI::RuntimeError(2);
    }
    return config;
  }
};

}  // namespace

void RegisterPingCommand(CLI::App& rslam) {
  auto* cmd = rslam.add_subcommand("ping", "publish a heartbeat as service `ping` for a while (checks a deployment's connectivity with `rslam status` elsewhere)");
  struct Args {
    DiagnosticBusArgs bus;
    double seconds = 10;
  };
  auto args = std::make_shared<Args>();
  args->bus.AddFlags(cmd);
  cmd->add_option("--robot", args->bus.robot, "robot id to publish as");
  cmd->add_option("--seconds", args->seconds, "how long to publish");
  cmd->callback([args] {
    BlockShutdownSignals();
    ServiceRuntimeConfig runtime;
    runtime.heartbeat_period_s = 0.2;
    ServiceContext context("ping", bus::Participant::Create(args->bus.Resolve("robot1")), runtime);
    Heartbeat heartbeat(context);
    struct Tick {
      Heartbeat& h;
      std::chrono::steady_clock::time_point end;
    } tick{heartbeat, std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<int64_t>(args->seconds * 1000))};
    heartbeat.Publish("running");
    WaitForShutdown(std::chrono::milliseconds(200), [](void* a) {
      auto* t = static_cast<Tick*>(a);
      t->h.Publish("running");
      if (std::chrono::steady_clock::now() >= t->end) RequestShutdown();
    }, &tick);
  });
}

void RegisterStatusCommand(CLI::App& rslam) {
  auto* cmd = rslam.add_subcommand("status", "show the live services of every robot (from rslam/status heartbeats)");
  struct Args {
    DiagnosticBusArgs bus;
    double wait_s = 2.0;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  args->bus.AddFlags(cmd);
  cmd->add_option("--wait", args->wait_s, "seconds to listen for heartbeats");
  cmd->add_flag("--json", args->json, "print JSON");
  cmd->callback([args] {
    const bus::BusConfig config = args->bus.Resolve("rslam-status");
    auto participant = bus::Participant::Create(config);
    bus::Subscriber<msg::ServiceStatus> sub(*participant, bus::topics::kStatus, bus::kAllRobots);
    std::map<std::pair<std::string, std::string>, msg::ServiceStatus> latest;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<int64_t>(args->wait_s * 1000));
    while (std::chrono::steady_clock::now() < deadline) {
      sub.Wait(std::chrono::milliseconds(50));
      for (auto& s : sub.Take()) latest[{s.header.robot_id, s.service}] = s;
    }
    if (args->json) {
      nlohmann::json out = nlohmann::json::array();
      for (const auto& [key, s] : latest) {
        nlohmann::json endpoints = nlohmann::json::array();
        for (const msg::EndpointMatch& e : s.endpoints)
          endpoints.push_back({{"topic", e.topic}, {"writer", e.writer}, {"matched", e.matched}});
        out.push_back({{"robot", s.header.robot_id}, {"service", s.service}, {"pid", s.pid}, {"state", s.state},
                       {"dds", s.dds_vendor}, {"uptime_s", s.uptime_s}, {"messages_in", s.messages_in},
                       {"messages_out", s.messages_out}, {"messages_rejected", s.messages_rejected},
                       {"processing_ms_mean", s.processing_ms_mean}, {"last_frame", s.header.frame_seq},
                       {"endpoints", endpoints}});
      }
      std::cout << out.dump(2) << std::endl;
      return;
    }
    if (latest.empty()) {
      std::cout << "no rslam services seen on domain " << config.domain_id << " (" << config.dds << ")\n";
      return;
    }
    std::cout << std::left << std::setw(10) << "ROBOT" << std::setw(16) << "SERVICE" << std::setw(9) << "STATE"
              << std::setw(8) << "PID" << std::setw(9) << "DDS" << std::setw(10) << "UPTIME" << std::setw(10) << "IN"
              << std::setw(10) << "OUT" << std::setw(9) << "REJECTED" << std::setw(9) << "MS/MSG"
              << "UNMATCHED\n";
    for (const auto& [key, s] : latest) {
      // Readers no writer has matched and writers no reader has: a stage whose input is missing.
      std::string unmatched;
      for (const msg::EndpointMatch& e : s.endpoints)
        if (e.matched == 0) unmatched += (unmatched.empty() ? "" : " ") + std::string(e.writer ? ">" : "<") + e.topic;
      std::cout << std::left << std::setw(10) << s.header.robot_id << std::setw(16) << s.service << std::setw(9)
                << s.state << std::setw(8) << s.pid << std::setw(9) << s.dds_vendor << std::setw(10)
                << (std::to_string(static_cast<int>(s.uptime_s)) + "s") << std::setw(10) << s.messages_in
                << std::setw(10) << s.messages_out << std::setw(9) << s.messages_rejected << std::fixed
                << std::setprecision(3) << std::setw(9) << s.processing_ms_mean << unmatched << "\n";
    }
  });
}

}  // namespace rslam::launch
