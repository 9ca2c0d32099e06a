#include "tools/demo/demo_command.h"

#include <unistd.h>

#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <numbers>
#include <nlohmann/json.hpp>
#include <sstream>

#include "common/bus/bus_config.h"
#include "common/config/config_loader.h"
#include "common/node/service_context.h"
#include "common/node/shutdown_signal.h"
#include "tools/demo/demo_artifacts.h"
#include "tools/demo/demo_metrics.h"
#include "tools/demo/demo_monitor.h"
#include "services/experience_map/experience_map_node_config.h"
#include "tools/launch/launch_command.h"
#include "tools/launch/launch_profile.h"
#include "tools/launch/process_supervisor.h"
#include "tools/sim/sim_node.h"

namespace rslam::demo {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr int kDefaultDomain = 17;
// Started in this order (and stopped in reverse: the simulator first, the recorder last).
const std::vector<std::string> kServices = {"camera",         "odometry",  "templates", "pose_cells",
                                            "experience_map", "occupancy", "explorer"};

std::string ResolveDds(const std::string& flag) {
  if (!flag.empty()) return flag;
  if (const char* env = std::getenv("RSLAM_DDS"); env != nullptr && *env != '\0') return env;
  return "cyclone";
}

int ResolveDomain(int flag) {
  if (flag >= 0) return flag;
  if (const char* env = std::getenv("RSLAM_DOMAIN"); env != nullptr && *env != '\0') return std::atoi(env);
  return kDefaultDomain;
}

// Old logs, state and results of a previous run in the same folder would mix with this run's.
void PrepareOutputDir(const fs::path& out) {
  fs::create_directories(out / "logs");
  fs::create_directories(out / "state");
  for (const auto& [dir, ext] : {std::pair{out / "logs", ".log"}, std::pair{out / "state", ".pb"}})
    for (const auto& entry : fs::directory_iterator(dir))
      if (entry.is_regular_file() && entry.path().extension() == ext) fs::remove(entry.path());
  for (const char* name : {"summary.json", "report.txt", "experience_map.png", "occupancy.png", "grid_errors.png", "grid.pgm",
                           "grid.yaml", "recording.mcap", "trajectories.csv", "experiences.csv"}) {
    std::error_code ignored;
    fs::remove(out / name, ignored);
  }
}

bool RecordCommandAvailable(const std::string& bin_dir) {
  const std::string rslam = (fs::path(bin_dir) / "rslam").string();
  if (::access(rslam.c_str(), X_OK) != 0) return false;
  return std::system(("'" + rslam + "' record --help >/dev/null 2>&1").c_str()) == 0;
}

const char* StateName(std::optional<msg::ExplorationState> s) {
  if (!s) return "-";
  switch (*s) {
    case msg::ExplorationState::EXPLORATION_WAITING: return "waiting";
    case msg::ExplorationState::EXPLORATION_EXPLORING: return "exploring";
    case msg::ExplorationState::EXPLORATION_COMPLETE: return "complete";
    case msg::ExplorationState::EXPLORATION_STOPPED: return "stopped";
  }
  return "?";
}

std::string Percent(std::optional<double> v) {
  if (!v) return "n/a";
  std::ostringstream s;
  s << std::fixed << std::setprecision(1) << 100.0 * *v << "%";
  return s.str();
}

std::string Metres(std::optional<double> v) {
  if (!v) return "n/a";
  std::ostringstream s;
  s << std::fixed << std::setprecision(3) << *v << " m";
  return s.str();
}

// Where the grid loses coverage and precision, as shares of the reachable and of the marked cells;
// empty without a grid.
std::string GridLosses(const std::optional<GridComparison>& g) {
  if (!g) return "";
  const auto share = [](uint64_t part, uint64_t whole) {
    return Percent(whole == 0 ? std::nullopt : std::optional(static_cast<double>(part) / whole));
  };
  return "  not covered:    " + share(g->missed_unknown_cells, g->reachable_cells) + " unknown, " +
         share(g->missed_uncertain_cells, g->reachable_cells) + " uncertain, " +
         share(g->missed_occupied_cells, g->reachable_cells) + " occupied (of the reachable cells)\n" +
         "  not agreeing:   " + share(g->wrong_free_cells, g->marked_cells) + " free where the world is wall, " +
         share(g->wrong_occupied_cells, g->marked_cells) + " occupied where it is free (of the marked cells)\n";
}

// Per frame: ground truth (world), experience-map pose (map frame), odometry and its dead
// reckoning, for plotting and for calibrating the odometry against the truth.
void WriteTrajectoriesCsv(const DemoObservations& seen, const std::vector<FramePose>& dead_reckoning,
                          const fs::path& path) {
  struct Row {
    const FramePose* truth = nullptr;
    const FramePose* map = nullptr;
    const FrameVelocity* odometry = nullptr;
    const FramePose* reckoned = nullptr;
  };
  std::map<uint64_t, Row> rows;
  for (const auto& p : seen.ground_truth) rows[p.frame_seq].truth = &p;
  for (const auto& p : seen.experience_poses) rows[p.frame_seq].map = &p;
  for (const auto& v : seen.odometry) rows[v.frame_seq].odometry = &v;
  for (const auto& p : dead_reckoning) rows[p.frame_seq].reckoned = &p;
  std::ofstream csv(path);
  csv << "frame_seq,stamp_ns,truth_x,truth_y,truth_theta,map_x,map_y,map_theta,vtrans_mps,vrot_radps,dt_s,"
         "odometry_x,odometry_y,odometry_theta\n";
  csv << std::setprecision(9);
  auto pose = [&csv](const FramePose* p) {
    if (p) csv << "," << p->x << "," << p->y << "," << p->theta;
    else csv << ",,,";
  };
  for (const auto& [seq, row] : rows) {
    const int64_t stamp = row.truth ? row.truth->stamp_ns : (row.map ? row.map->stamp_ns : 0);
    csv << seq << "," << stamp;
    pose(row.truth);
    pose(row.map);
    if (row.odometry) csv << "," << row.odometry->vtrans_mps << "," << row.odometry->vrot_radps << "," << row.odometry->dt_s;
    else csv << ",,,";
    pose(row.reckoned);
    csv << "\n";
  }
}

struct TickContext {
  std::function<void()> tick;
};

}  // namespace

int RunDemo(const DemoOptions& options) {
  // Before any thread starts (the bus starts several): every thread must block the shutdown
  // signals, or RequestShutdown's signal would kill the process instead of ending the wait.
  BlockShutdownSignals();
  const auto wall_start = Clock::now();
  const std::string bin_dir = options.bin_dir.empty() ? launch::ExecutableDir() : options.bin_dir;
  const std::string config_path =
      options.config.empty() ? launch::DeployDir() + "/config/demo.yaml" : fs::absolute(options.config).string();
  const std::string dds = ResolveDds(options.dds);
  const int domain = ResolveDomain(options.domain);
  const fs::path out = fs::absolute(options.out_dir);
  PrepareOutputDir(out);

  // The world and start pose, as the simulator will see them.
  YAML::Node root = LoadYamlFile(config_path);
  std::vector<std::string> extra_args;
  if (!options.world.empty()) {
    const std::string world = fs::exists(options.world) ? fs::absolute(options.world).string() : options.world;
    ApplyOverride(root, "sim.world_yaml=" + world);
    extra_args.insert(extra_args.end(), {"--set", "sim.world_yaml=" + world});
  }
  if (options.wheel_odometry) extra_args.insert(extra_args.end(), {"--set", "odometry.use_wheel_odometry=true"});
  sim::SimNodeConfig sim_config;
  LoadConfigSection(root, "sim", sim_config);
  const std::string world_path = sim::ResolveWorldPath(sim_config.sim.world_yaml);
  const sim::WorldMap world = sim::WorldMap::LoadFromYaml(world_path);
  const Pose2D start = sim::StartPoseOf(sim_config, world);
  const std::vector<Eigen::Vector2i> reachable =
      ReachableFootprint(world, start, sim_config.sim.motion.robot_radius_m);
  // The map frame in the world (the experience map's first facing is OpenRatSLAM's 90 degrees
  // unless configured).
  experience_map::ExperienceMapNodeConfig map_config;
  LoadConfigSection(root, "experience_map", map_config);
  const Pose2D map_origin = MapOrigin(start, map_config.map.exp_initial_em_deg * std::numbers::pi / 180);
  // Each service bounds its own stop by service.stop_timeout_s (its state saved first); the launcher
  // kills a second after that.
  ServiceRuntimeConfig runtime;
  LoadConfigSection(root, "service", runtime);

  std::cout << "rslam demo: " << world_path << " (" << reachable.size() << " reachable free cells), start ("
            << start.x << ", " << start.y << ", " << start.theta << "), " << dds << " domain " << domain
            << ", up to " << options.max_seconds << " s\n"
            << "output: " << out.string() << "\n";

  // Watch the bus before anything starts, so nothing is missed.
  bus::BusConfig bus_config;
  bus_config.dds = dds;
  bus_config.domain_id = domain;
  bus_config.robot_id = options.robot;
  auto participant = bus::Participant::Create(bus_config);
  DemoMonitor monitor(*participant, options.robot);

  launch::LaunchProfile profile;
  profile.restart = {.backoff_initial_s = 0.5, .backoff_max_s = 4, .max_restarts = 3};
  const bool record = RecordCommandAvailable(bin_dir);
  const fs::path recording = out / "recording.mcap";
  if (record) {
    launch::LaunchEntry recorder;
    recorder.name = "recorder";
    recorder.command = {"rslam", "record", "-o", recording.string(), "--robot", options.robot};
    if (!options.record_images) recorder.command.insert(recorder.command.end(), {"--exclude", "^(sim/camera|camera/image)$"});
    profile.processes.push_back(recorder);
  }
  for (const std::string& name : kServices) profile.processes.emplace_back().name = name;
  profile.processes.emplace_back().name = "sim";
  launch::LaunchOptions launch_options{.bin_dir = bin_dir,
                                       .robot = options.robot,
                                       .dds = dds,
                                       .domain = domain,
                                       .config = config_path,
                                       .log_dir = (out / "logs").string(),
                                       .state_dir = (out / "state").string(),
                                       .extra_args = extra_args};
  std::vector<std::string> missing;
  std::vector<std::string> notes;
  if (!record) notes.push_back("no recording: `rslam record` is not available in " + bin_dir);

  launch::ProcessSupervisor supervisor(profile.restart);
  std::ofstream events(out / "logs" / "demo.log");
  supervisor.OnEvent([&events](const std::string& e) { events << e << std::endl; });
  for (const auto& spec : launch::BuildProcessSpecs(profile, launch_options)) {
    if (::access(spec.executable.c_str(), X_OK) != 0) {
      missing.push_back(spec.name);
      continue;
    }
    supervisor.Start(spec);
  }
  if (!missing.empty()) {
    std::string list;
    for (const auto& m : missing) list += (list.empty() ? "" : ", ") + m;
    notes.push_back("not built, so not started: " + list);
    std::cout << "warning: " << notes.back() << "\n";
  }

  // Run until exploration completes, time runs out, a process gives up, or Ctrl-C.
  const bool tty = ::isatty(STDOUT_FILENO) != 0;
  std::string end_reason = "interrupted";
  bool complete = false;
  auto last_print = Clock::now() - std::chrono::hours(1);
  uint64_t last_grid_version = 0;
  std::optional<double> live_coverage;
  TickContext ctx;
  ctx.tick = [&] {
    supervisor.Poll();
    const double elapsed = std::chrono::duration<double>(Clock::now() - wall_start).count();
    const DemoProgress p = monitor.Progress();
    const auto now = Clock::now();
    const bool print = now - last_print >= (tty ? std::chrono::milliseconds(500) : std::chrono::milliseconds(5000));
    if (print && p.grid_version != last_grid_version) {
      last_grid_version = p.grid_version;
      if (auto grid = monitor.LatestGrid()) {
        try {
          live_coverage = CompareGridWithWorld(world, reachable, map_origin, *grid, world.resolution()).coverage;
        } catch (const std::exception&) {
        }
      }
    }
    if (print) {
      last_print = now;
      std::ostringstream line;
      line << std::fixed << std::setprecision(0) << std::setw(4) << elapsed << " s  frames " << p.frames << "  coverage "
           << Percent(live_coverage) << "  experiences " << p.experience_count << "  templates " << p.template_count
           << "  explorer " << StateName(p.explorer_state);
      if (tty)
        std::cout << "\r" << std::left << std::setw(100) << line.str() << std::flush;
      else
        std::cout << line.str() << std::endl;
    }
    if (p.explorer_state == msg::ExplorationState::EXPLORATION_COMPLETE) {
      complete = true;
      end_reason = "exploration complete";
      RequestShutdown();
    } else if (elapsed >= options.max_seconds) {
      end_reason = "time limit (" + std::to_string(static_cast<int>(options.max_seconds)) + " s)";
      RequestShutdown();
    } else {
      for (const auto& s : supervisor.Statuses())
        if (s.gave_up) {
          end_reason = s.name + " gave up (" + s.last_exit + "; see logs/" + s.name + ".log)";
          RequestShutdown();
        }
    }
  };
  WaitForShutdown(std::chrono::milliseconds(100), [](void* a) { static_cast<TickContext*>(a)->tick(); }, &ctx);
  if (tty) std::cout << "\n";
  std::cout << "stopping: " << end_reason << std::endl;
  const double wall_s = std::chrono::duration<double>(Clock::now() - wall_start).count();
  const auto statuses_before_stop = supervisor.Statuses();
  const bool stopped_cleanly =
      supervisor.StopAll(std::chrono::milliseconds(std::llround((runtime.stop_timeout_s + 1) * 1000)));
  if (!stopped_cleanly) notes.push_back("some processes had to be killed at the end (see logs/demo.log)");

  // Results.
  const DemoObservations seen = monitor.Snapshot();
  const RunFigures figures = JudgeRun(world, reachable, map_origin, seen);
  const std::optional<GridComparison>& grid_check = figures.grid;
  const std::optional<GridComparison>& grid_at_start = figures.grid_at_start;
  if (seen.grid) {
    WriteMapServerGrid(*seen.grid, out / "grid");
    cv::imwrite((out / "occupancy.png").string(), RenderOccupancy(*seen.grid, seen.experience_poses));
    cv::imwrite((out / "grid_errors.png").string(),
                RenderGridComparison(world, reachable, figures.map_to_world.value_or(map_origin), *seen.grid,
                                     world.resolution()));
  } else {
    notes.push_back("no occupancy grid was received: no coverage, precision, grid files, occupancy.png or grid_errors.png");
  }
  const LoopClosureCheck& loops = figures.loops;
  auto ate_of = [](const std::optional<eval::TrajectoryError>& e) {
    return e ? std::optional(e->ate_m) : std::nullopt;
  };
  cv::imwrite((out / "experience_map.png").string(),
              RenderExperienceMap(world, seen.ground_truth, seen.map ? &*seen.map : nullptr,
                                  figures.ate ? &*figures.ate : nullptr));
  WriteTrajectoriesCsv(seen, figures.dead_reckoning, out / "trajectories.csv");
  if (seen.map) WriteExperiencesCsv(*seen.map, seen, figures.ate ? &*figures.ate : nullptr, out / "experiences.csv");
  const uint64_t frames = seen.ground_truth.size();
  const uint32_t experiences = seen.map ? static_cast<uint32_t>(seen.map->experiences.size()) : seen.experience_count;
  const auto& ate = figures.ate;
  const auto& ate_odometry = figures.ate_odometry;
  const auto& ate_live = figures.ate_live;
  const auto& ate_odometry_all = figures.ate_odometry_all;

  nlohmann::json summary = FiguresJson(figures, seen, map_origin, world.resolution());
  summary["complete"] = complete;
  summary["end_reason"] = end_reason;
  summary["wall_s"] = wall_s;
  summary["dds"] = dds;
  summary["domain"] = domain;
  summary["world"] = world_path;
  summary["start_pose"] = {start.x, start.y, start.theta};
  summary["odometry"] = options.wheel_odometry ? "wheel" : "visual";
  nlohmann::json processes = nlohmann::json::object();
  for (const auto& s : statuses_before_stop)
    processes[s.name] = {{"restarts", s.restarts}, {"running_at_end", s.running}, {"gave_up", s.gave_up},
                         {"last_exit", s.last_exit}};
  summary["processes"] = processes;
  summary["missing"] = missing;
  summary["recording"] = record ? nlohmann::json(recording.string()) : nlohmann::json(nullptr);
  summary["notes"] = notes;
  std::ofstream(out / "summary.json") << summary.dump(2) << "\n";

  std::ostringstream report;
  report << "rslam demo: " << (complete ? "exploration complete" : "exploration NOT complete") << " (" << end_reason
         << ") after " << std::fixed << std::setprecision(0) << wall_s << " s wall, " << frames << " frames ("
         << std::setprecision(1) << frames * sim_config.sim.motion.time_step_s << " s simulated), " << dds
         << " domain " << domain << "\n"
         << "world: " << world_path << ", start (" << std::setprecision(2) << start.x << ", " << start.y << ", "
         << start.theta << ")\n"
         << "odometry used by the map: " << (options.wheel_odometry ? "wheel" : "visual (camera only)") << "\n\n"
         << "coverage            " << Percent(grid_check ? std::optional(grid_check->coverage) : std::nullopt)
         << "  of the free cells the robot's footprint can reach from the start\n"
         << "map precision       " << Percent(grid_check ? std::optional(grid_check->precision) : std::nullopt)
         << "  of the grid's free/occupied cells agree with the world (within one world cell)\n"
         << GridLosses(grid_check)
         << "templates           " << seen.template_count << "\n"
         << "experiences         " << experiences << ", links " << loops.links << ", loop closures "
         << loops.loop_closures << "\n"
         << "loop closures right " << Percent(loops.precision) << "  (both experiences within "
         << kLoopClosureMaxDistanceM << " m in ground truth; the farthest apart " << Metres(loops.farthest_m) << ")\n"
         << "ATE experience map  " << Metres(ate_of(ate))
         << "  (final map: each experience against the true pose it was made at; similarity-aligned)\n"
         << "ATE odometry        " << Metres(ate_of(ate_odometry))
         << "  (dead reckoning of odometry/velocity at the same frames, same alignment)\n"
         << "ATE live path       " << Metres(ate_of(ate_live)) << "  (the map's pose at each frame, as it was then; odometry "
         << Metres(ate_of(ate_odometry_all)) << ")\n\n"
         << "The map frame starts at the robot's start pose (turned by the map's initial facing). Coverage and\n"
         << "precision place the grid in the world by the rigid fit of the experiences to their ground truth\n"
         << "(the map's shape, as ATE judges it); placed by the start pose alone they are "
         << Percent(grid_at_start ? std::optional(grid_at_start->coverage) : std::nullopt) << " and "
         << Percent(grid_at_start ? std::optional(grid_at_start->precision) : std::nullopt) << ".\n";
  for (const auto& n : notes) report << "note: " << n << "\n";
  report << "\nfiles: summary.json, report.txt, experience_map.png, occupancy.png, grid_errors.png, grid.pgm, grid.yaml, "
            "trajectories.csv"
         << (seen.map ? ", experiences.csv" : "") << (record ? ", recording.mcap" : "") << ", logs/, state/\n";
  std::ofstream(out / "report.txt") << report.str();
  std::cout << "\n" << report.str();
  return 0;
}

void RegisterDemoCommand(CLI::App& rslam) {
  auto* cmd = rslam.add_subcommand(
      "demo", "a simulated robot explores a room with every service as its own process; writes map, metrics, recording");
  auto options = std::make_shared<DemoOptions>();
  cmd->add_option("--out", options->out_dir, "output folder")->capture_default_str();
  cmd->add_option("--world", options->world, "world map (map_server YAML); default: deploy/worlds/uwb-room.yaml");
  cmd->add_option("--dds", options->dds, "DDS vendor for every process (default: env RSLAM_DDS, else cyclone)")
      ->check(CLI::IsMember({"cyclone", "fastdds"}));
  cmd->add_option("--domain", options->domain, "DDS domain id (default: env RSLAM_DOMAIN, else 17)")
      ->check(CLI::Range(0, 229));
  cmd->add_option("--max-seconds", options->max_seconds, "stop after this many seconds even if not complete")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--wheel-odometry", options->wheel_odometry, "map with the wheel odometry instead of visual odometry");
  cmd->add_flag("--record-images", options->record_images, "also record camera images (large)");
  cmd->add_option("--config", options->config, "config file for every process (default: deploy/config/demo.yaml)")
      ->check(CLI::ExistingFile);
  cmd->callback([options] {
    int code = 0;
    try {
      code = RunDemo(*options);
    } catch (const ConfigError& e) {
      std::cerr << "rslam demo: config error: " << e.what() << std::endl;
      throw CLI::RuntimeError(2);
    } catch (const std::exception& e) {
      std::cerr << "rslam demo: " << e.what() << std::endl;
      throw CLI::RuntimeError(1);
    }
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace rslam::demo
