#include "tools/record/record_command.h"

#include <chrono>
#include <cmath>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "common/bus/participant.h"
#include "common/config/config_error.h"
#include "common/mcap/mcap_recovery.h"
#include "common/mcap/mcap_records.h"
#include "common/node/shutdown_signal.h"
#include "tools/record/player.h"
#include "tools/record/recorder.h"
#include "tools/record/recording_info.h"

namespace rslam::record {
namespace {

using namespace std::chrono_literals;

struct BusFlags {
  std::string dds;  // "" = config / environment
  int domain = -1;  // -1 = environment or 0
};

void AddBusFlags(CLI::App* cmd, BusFlags& flags) {
  cmd->add_option("--dds", flags.dds, "DDS vendor: cyclone or fastdds (default: env RSLAM_DDS, else cyclone)")
      ->check(CLI::IsMember({"cyclone", "fastdds"}));
  cmd->add_option("--domain", flags.domain, "DDS domain id (default: env RSLAM_DOMAIN, else 0)")->check(CLI::Range(0, 229));
}

// Environment first, then the flags (flags win).
bus::BusConfig MakeBusConfig(const BusFlags& flags, const std::string& name) {
  bus::BusConfig config;
  config.robot_id = name;
  try {
    config.ApplyEnvironment();
    if (!flags.dds.empty()) config.dds = flags.dds;
    if (flags.domain >= 0) config.domain_id = flags.domain;
    config.Validate();
  } catch (const ConfigError& e) {
    std::cerr << "rslam " << name.substr(name.find('-') + 1) << ": " << e.what() << std::endl;
    throw CLI::RuntimeError(2);
  }
  return config;
}

[[noreturn]] void Fail(const std::string& command, const std::string& what, int code = 1) {
  std::cerr << "rslam " << command << ": " << what << std::endl;
  throw CLI::RuntimeError(code);
}

// ---------------------------------------------------------------- record

struct RecordArgs {
  std::string output;
  std::string topics;
  std::string exclude;
  std::vector<std::string> robots;
  double split_size_mb = 0;
  double split_duration_s = 0;
  std::string compression = "zstd";
  int zstd_level = 1;
  double duration_s = 0;
  double queue_mb = 1024;
  double stop_timeout_s = 5;
  BusFlags bus;
};

struct RecordLoop {
  Recorder& recorder;
  std::map<std::string, int> matched;  // "topic@partition" -> writers last reported
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
  bool shutdown_requested = false;
};

void ReportMatches(RecordLoop& loop) {
  for (const auto& s : loop.recorder.Subscriptions()) {
    const std::string key = s.topic + " (robot " + s.partition + ")";
    auto [it, fresh] = loop.matched.try_emplace(key, 0);
    if (it->second != s.matched_writers) {
      it->second = s.matched_writers;
      std::cerr << "[record] " << key << ": " << s.matched_writers << " publisher(s)" << std::endl;
    }
  }
}

void OnRecordTick(void* arg) {
  auto& loop = *static_cast<RecordLoop*>(arg);
  ReportMatches(loop);
  if (loop.shutdown_requested) return;
  if (loop.recorder.error() || std::chrono::steady_clock::now() >= loop.deadline) {
    loop.shutdown_requested = true;
    RequestShutdown();
  }
}

void RegisterRecord(CLI::App& rslam) {
  auto* cmd = rslam.add_subcommand("record", "record DDS topics into an MCAP file (Ctrl-C to stop)");
  auto args = std::make_shared<RecordArgs>();
  cmd->add_option("-o,--output", args->output, "MCAP file to write (the base name when splitting)")->required();
  cmd->add_option("--topics", args->topics, "record only topics matching this regular expression (searched)");
  cmd->add_option("--exclude", args->exclude, "skip topics matching this regular expression");
  cmd->add_option("--robot", args->robots, "record this robot (repeatable; default: every robot)");
  auto* size = cmd->add_option("--split-size", args->split_size_mb, "start a new file every MB megabytes")
                   ->check(CLI::PositiveNumber);
  cmd->add_option("--split-duration", args->split_duration_s, "start a new file every S seconds")
      ->check(CLI::PositiveNumber)
      ->excludes(size);
  cmd->add_option("--compression", args->compression, "chunk compression")
      ->capture_default_str()
      ->check(CLI::IsMember({"zstd", "lz4", "none"}));
  cmd->add_option("--zstd-level", args->zstd_level, "zstd level: 1 is fast, negative faster, up to 19 smaller")
      ->capture_default_str()
      ->check(CLI::Range(-5, 19));
  cmd->add_option("--duration", args->duration_s, "stop after S seconds (default: until Ctrl-C)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--queue-mb", args->queue_mb, "memory for messages waiting to be written; beyond it they are dropped")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--stop-timeout", args->stop_timeout_s,
                  "once the file is finished, exit anyway if leaving the bus takes longer than S seconds")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  AddBusFlags(cmd, args->bus);
  cmd->callback([args] {
    const bus::BusConfig config = MakeBusConfig(args->bus, "rslam-record");
    RecorderOptions options;
    options.file.path = args->output;
    options.file.compression = args->compression;
    options.file.compression_level = args->zstd_level;
    options.file.split_bytes = static_cast<uint64_t>(std::llround(args->split_size_mb * 1e6));
    options.file.split_duration_ns = static_cast<uint64_t>(std::llround(args->split_duration_s * 1e9));
    options.topics_regex = args->topics;
    options.exclude_regex = args->exclude;
    options.robots = args->robots;
    options.queue_bytes = static_cast<std::size_t>(args->queue_mb * 1e6);

    BlockShutdownSignals();  // before DDS starts its threads
    // Declared first, so destroyed last: armed once the file is finished, it bounds the bus
    // teardown after it (the services' stop_timeout_s, for the same Fast DDS hang).
    std::optional<ExitDeadline> teardown_deadline;
    std::unique_ptr<bus::Participant> participant;
    std::unique_ptr<Recorder> recorder;
    try {
      participant = bus::Participant::Create(config);
      recorder = std::make_unique<Recorder>(*participant, options);
    } catch (const std::exception& e) {
      Fail("record", e.what());
    }
    std::string topics;
    for (const auto& t : recorder->topics()) topics += " " + t.name;
    std::cerr << "[record] recording " << recorder->topics().size() << " topics (robots: "
              << (args->robots.empty() ? std::string("all") : CLI::detail::join(args->robots, ", ")) << ", "
              << config.dds << ", domain " << config.domain_id << ") to " << recorder->paths().front() << " ("
              << args->compression << "):" << topics << std::endl;

    RecordLoop loop{*recorder, {}};
    if (args->duration_s > 0)
      loop.deadline = std::chrono::steady_clock::now() +
                      std::chrono::milliseconds(static_cast<int64_t>(args->duration_s * 1000));
    WaitForShutdown(100ms, &OnRecordTick, &loop);

    std::cerr << "[record] stopping" << std::endl;
    std::string error;
    try {
      recorder->Stop();
    } catch (const std::exception& e) {
      error = e.what();
    }
    const RecorderStats st = recorder->Stats();
    std::cerr << "[record] " << st.written << " messages in " << st.channels << " channels (received " << st.received
              << ", dropped " << st.dropped << ", without robot id " << st.unattributed << ") ->";
    for (const auto& p : recorder->paths()) std::cerr << " " << p;
    std::cerr << std::endl;
    if (st.dropped > 0)
      std::cerr << "[record] warning: " << st.dropped << " messages dropped: the disk did not keep up (raise --queue-mb)"
                << std::endl;
    if (!error.empty()) Fail("record", "writing failed: " + error);
    teardown_deadline.emplace(std::chrono::milliseconds(std::llround(args->stop_timeout_s * 1000)),
                              "leaving the bus");
  });
}

// ---------------------------------------------------------------- play

struct PlayArgs {
  std::vector<std::string> files;
  PlayOptions options;
  std::vector<std::string> remaps;
  double wait_timeout_s = 5.0;
  BusFlags bus;
};

void RegisterPlay(CLI::App& rslam) {
  auto* cmd = rslam.add_subcommand("play", "publish a recording's messages on the bus again");
  auto args = std::make_shared<PlayArgs>();
  cmd->add_option("files", args->files, "MCAP file(s); several are played one after the other (split recordings)")
      ->required()
      ->check(CLI::ExistingFile);
  auto* rate = cmd->add_option("--rate", args->options.rate, "playback speed factor (2 = twice as fast)")
                   ->capture_default_str()
                   ->check(CLI::PositiveNumber);
  cmd->add_flag("--max", args->options.max_speed, "as fast as reliable readers take the messages, losing none")
      ->excludes(rate);
  cmd->add_flag("--loop", args->options.loop, "play again from the start until Ctrl-C");
  cmd->add_option("--start", args->options.start_s, "start S seconds into the recording")->check(CLI::NonNegativeNumber);
  cmd->add_option("--end", args->options.end_s, "stop S seconds into the recording")->check(CLI::NonNegativeNumber);
  cmd->add_option("--topics", args->options.topics_regex, "play only topics matching this regular expression");
  cmd->add_option("--robot-remap", args->remaps, "publish robot A's messages as robot B (A=B, repeatable)");
  cmd->add_option("--wait-for-readers", args->options.wait_for_readers,
                  "before starting, wait until every topic has N matched readers (0 = do not wait)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--wait-timeout", args->wait_timeout_s, "give up waiting for readers after S seconds")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  AddBusFlags(cmd, args->bus);
  cmd->callback([args] {
    PlayOptions options = args->options;
    try {
      for (const auto& r : args->remaps) options.robot_remap.insert(ParseRobotRemap(r));
    } catch (const std::invalid_argument& e) {
      Fail("play", e.what(), 2);
    }
    options.wait_timeout = std::chrono::milliseconds(static_cast<int64_t>(args->wait_timeout_s * 1000));
    options.on_event = [](const std::string& e) { std::cerr << "[play] " << e << std::endl; };
    const bus::BusConfig config = MakeBusConfig(args->bus, "rslam-play");

    BlockShutdownSignals();
    std::unique_ptr<bus::Participant> participant;
    try {
      participant = bus::Participant::Create(config);
    } catch (const std::exception& e) {
      Fail("play", e.what());
    }
    PlayReport report;
    std::string error;
    std::jthread player([&](std::stop_token stop) {
      try {
        report = PlayFiles(*participant, args->files, options, stop);
      } catch (const std::exception& e) {
        error = e.what();
      }
      RequestShutdown();
    });
    WaitForShutdown();
    player.request_stop();
    player.join();
    if (!error.empty()) Fail("play", error);
    std::cerr << "[play] published " << report.messages << " messages on " << report.channels.size() << " channels"
              << (report.stopped ? " (stopped)" : "") << std::endl;
    for (const auto& c : report.channels)
      std::cerr << "[play]   " << c.dds_topic << " (robot " << c.partition
                << (c.partition == c.recorded_robot ? std::string() : " <- " + c.recorded_robot) << ", " << c.qos
                << "): " << c.messages << std::endl;
    if (report.ack_timeouts > 0)
      std::cerr << "[play] warning: " << report.ack_timeouts << " messages not acknowledged in time" << std::endl;
    if (report.malformed > 0)
      std::cerr << "[play] warning: " << report.malformed << " malformed messages skipped" << std::endl;
  });
}

// ---------------------------------------------------------------- info

struct InfoArgs {
  std::string file;
  bool json = false;
  std::string recover;
};

void RegisterInfo(CLI::App& rslam) {
  auto* cmd = rslam.add_subcommand("info", "describe a recording; refuse a damaged one; --recover repairs it");
  auto args = std::make_shared<InfoArgs>();
  cmd->add_option("file", args->file, "MCAP file")->required()->check(CLI::ExistingFile);
  cmd->add_flag("--json", args->json, "print JSON");
  cmd->add_option("--recover", args->recover,
                  "write a valid copy with every complete chunk (for a file left by a killed recorder) and describe it");
  cmd->callback([args] {
    nlohmann::json recovered;
    std::string path = args->file;
    try {
      if (!args->recover.empty()) {
        const mcap::RecoveryReport r = mcap::RecoverMcap(args->file, args->recover);
        recovered = {{"from", args->file}, {"messages", r.messages}, {"chunks", r.chunks}, {"bytes_dropped", r.bytes_dropped}};
        if (!args->json)
          std::cout << "Recovered " << r.messages << " messages from " << r.chunks << " complete chunks of " << args->file
                    << " (" << r.bytes_dropped << " bytes dropped) into " << args->recover << "\n\n";
        path = args->recover;
      }
      const RecordingInfo info = DescribeRecording(path);
      if (args->json) {
        nlohmann::json j = ToJson(info);
        if (!recovered.is_null()) j["recovered"] = recovered;
        std::cout << j.dump(2) << std::endl;
      } else {
        std::cout << FormatRecordingInfo(info);
      }
    } catch (const mcap::McapError& e) {
      std::string what = e.what();
      if (what.rfind(path, 0) != 0) what = path + ": " + what;
      if (what.find("RecoverMcap") != std::string::npos)
        what += "\n  repair it with: rslam info " + path + " --recover REPAIRED.mcap";
      Fail("info", what);
    } catch (const std::exception& e) {
      Fail("info", path + ": " + e.what());
    }
  });
}

}  // namespace

void RegisterRecordCommands(CLI::App& rslam) {
  RegisterRecord(rslam);
  RegisterPlay(rslam);
  RegisterInfo(rslam);
}

}  // namespace rslam::record
