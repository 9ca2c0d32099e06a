#pragma once
// RunService<Node>: the whole main() of a service. It parses the command line (--config,
// --robot, --dds, --domain, --set key=value, --state-dir, --fresh, --log-level, --help),
// loads the YAML config (sections `bus`, `service` and one named after the service), joins
// the bus, constructs the node, publishes heartbeats, calls the node's periodic hook, and on
// SIGINT/SIGTERM destroys the node (which saves its state) and exits 0. The whole stop is
// bounded by service.stop_timeout_s (ExitDeadline).
//
// A node is a class with
//   using Config = ...;                      // VisitFields/Validate struct, section `name`
//   Node(ServiceContext&, const Config&);
//   ~Node();                                 // stops, saves state
//   void Tick();                             // optional: every heartbeat period (periodic save)
// Exit codes: 0 clean stop, 2 bad command line or config (the message names the key),
// 1 any other start-up failure (bus, corrupt state file).

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <csignal>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "common/bus/bus_config.h"
#include "common/config/config_loader.h"
#include "common/log/logging.h"
#include "common/node/heartbeat.h"
#include "common/node/service_context.h"
#include "common/node/shutdown_signal.h"

namespace rslam {

// Top-level sections a config file may have (a file may configure several services).
bool IsKnownConfigSection(const std::string& name);

struct ServiceCommandLine {
  std::string config_file;
  std::string robot;
  std::string dds;
  int domain = -1;
  std::vector<std::string> overrides;
  std::string state_dir;
  bool fresh = false;
  std::string log_level;
};

// Adds the common flags to app.
void AddServiceFlags(CLI::App& app, ServiceCommandLine& cl);
// Builds the YAML tree from --config and --set, checking top-level sections.
YAML::Node LoadServiceYaml(const ServiceCommandLine& cl);
// Bus and runtime settings from YAML, environment and flags (flags win, then env, then file).
bus::BusConfig ResolveBusConfig(const YAML::Node& root, const ServiceCommandLine& cl);
ServiceRuntimeConfig ResolveRuntimeConfig(const YAML::Node& root, const ServiceCommandLine& cl);

template <class Node>
concept HasTick = requires(Node& n) { n.Tick(); };

template <class Node>
int RunService(const std::string& name, const std::string& description, int argc, char** argv) {
  BlockShutdownSignals();
  typename Node::Config defaults;
  CLI::App app{description, "rslam-" + name};
  ServiceCommandLine cl;
  AddServiceFlags(app, cl);
  app.footer("Config keys (section `" + name + "` of --config, or --set " + name + ".KEY=VALUE):\n" +
             DescribeConfig(defaults, name));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  typename Node::Config config;
  bus::BusConfig bus_config;
  ServiceRuntimeConfig runtime;
  try {
    const YAML::Node root = LoadServiceYaml(cl);
    LoadConfigSection(root, name, config);
    bus_config = ResolveBusConfig(root, cl);
    runtime = ResolveRuntimeConfig(root, cl);
    SetupLogging(name, runtime.log_level);
  } catch (const ConfigError& e) {
    std::cerr << "rslam-" << name << ": config error: " << e.what() << "\n";
    return 2;
  }
  try {
    // Declared first, so destroyed last: it bounds the whole stop, the node's and the bus's.
    std::optional<ExitDeadline> stop_deadline;
    ServiceContext context(name, bus::Participant::Create(bus_config), runtime);
    Heartbeat heartbeat(context);
    spdlog::info("starting on {} domain {} as robot {}", bus_config.dds, bus_config.domain_id, bus_config.robot_id);
    Node node(context, config);
    heartbeat.Publish("running");
    struct Tick {
      Node& node;
      Heartbeat& heartbeat;
    } tick{node, heartbeat};
    const int sig = WaitForShutdown(
        std::chrono::milliseconds(static_cast<int64_t>(runtime.heartbeat_period_s * 1000)),
        [](void* arg) {
          auto* t = static_cast<Tick*>(arg);
          if constexpr (HasTick<Node>) t->node.Tick();
          t->heartbeat.Publish("running");
        },
        &tick);
    spdlog::info("stopping ({})", sig == 0 ? "finished" : (sig == SIGINT ? "SIGINT" : "SIGTERM"));
    stop_deadline.emplace(std::chrono::milliseconds(static_cast<int64_t>(runtime.stop_timeout_s * 1000)), "the stop");
    heartbeat.Publish("stopping");
  } catch (const ConfigError& e) {
    spdlog::error("config error: {}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  return 0;
}

}  // namespace rslam
