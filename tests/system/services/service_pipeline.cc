#include "tests/system/services/service_pipeline.h"

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include "common/bus/bus_config.h"
#include "common/bus/topics.h"
#include "common/node/heartbeat.h"

namespace rslam::system_test {

std::string BinaryDir() {
  if (const char* dir = std::getenv("RSLAM_SYSTEM_TEST_BIN_DIR"); dir != nullptr && *dir != '\0')
    return std::string(dir) + "/";
  return RSLAM_BINARY_DIR "/bin/";
}

ServicePipeline::ServicePipeline(int domain, PipelineOptions options) : domain_(domain), options_(std::move(options)) {
  bus::BusConfig bus_config;
  bus_config.domain_id = domain_;
  participant_ = bus::Participant::Create(bus_config);
  pose_subscriber_ = std::make_unique<bus::Subscriber<msg::ExperiencePose>>(
      *participant_, bus::topics::kExperienceMapPose, [this](const msg::ExperiencePose& pose) {
        std::lock_guard lock(mutex_);
        poses_.push_back(pose);
      });
  map_subscriber_ = std::make_unique<bus::Subscriber<msg::ExperienceMap>>(
      *participant_, bus::topics::kExperienceMapMap, [this](const msg::ExperienceMap& map) {
        std::lock_guard lock(mutex_);
        if (!latest_map_ || map.action_seq >= latest_map_->action_seq) latest_map_ = map;
      });
  status_subscriber_ = std::make_unique<bus::Subscriber<msg::ServiceStatus>>(
      *participant_, bus::topics::kStatus, [this](const msg::ServiceStatus& status) {
        std::lock_guard lock(mutex_);
        running_[status.service] = status.state;
      });
  const auto await_running = [this](const std::vector<std::string>& names) {
    const bool up = testing::WaitFor(
        [&] {
          std::lock_guard lock(mutex_);
          for (const auto& n : names)
            if (running_.count(n) == 0 || running_.at(n) != "running") return false;
          return true;
        },
        options_.startup_timeout);
    if (!up) throw std::runtime_error("services did not report running in time\n" + Logs());
  };
  // Back to front: a stage's readers exist before the stage in front of it publishes.
  Start("experience-map");
  Start("pose-cells");
  await_running({"experience_map", "pose_cells"});
  Start("odometry");
  Start("templates");
  await_running({"odometry", "templates"});
  if (!pose_subscriber_->WaitForPublishers(1, options_.startup_timeout))
    throw std::runtime_error("experience_map/pose never matched\n" + Logs());
  AwaitDiscovery();
}

// "Running" says a service's readers and writers exist, not that discovery has matched them:
// across vendors that can take a second, and a stream sample written before its reader matched
// is never delivered (the first frames' odometry would be lost). The camera starts once the
// heartbeats show every link among the services matched at both ends.
void ServicePipeline::AwaitDiscovery() {
  const ServiceLinkWatch links(*participant_);
  std::vector<std::string> unmatched;
  const std::vector<std::string> services = {"odometry", "templates", "pose_cells", "experience_map"};
  if (testing::WaitFor([&] { return (unmatched = links.Unmatched(services)).empty(); }, options_.startup_timeout))
    return;
  std::string list;
  for (const auto& u : unmatched) list += u + "\n";
  throw std::runtime_error("discovery never matched:\n" + list + Logs());
}

ServicePipeline::~ServicePipeline() {
  camera_.reset();
  // Front to back, so no stage is left blocked on a dead reader.
  for (auto it = services_.begin(); it != services_.end(); ++it) (*it)->Signal(SIGTERM);
  services_.clear();
}

std::vector<std::string> ServicePipeline::ServiceArgs(const std::string& service) const {
  std::vector<std::string> args{"--domain", std::to_string(domain_), "--config", options_.config_file, "--fresh",
                                "--log-level", "info"};
  const auto vendor = options_.vendors.find(service);
  args.push_back("--dds");
  args.push_back(vendor == options_.vendors.end() ? "cyclone" : vendor->second);
  return args;
}

void ServicePipeline::Start(const std::string& service, const std::vector<std::string>& extra_args) {
  std::vector<std::string> args = ServiceArgs(service);
  args.insert(args.end(), extra_args.begin(), extra_args.end());
  testing::ChildProcess::Options child;
  if (!options_.log_dir.empty()) child.log_file = options_.log_dir + "/" + service + ".log";
  services_.push_back(std::make_unique<testing::ChildProcess>(BinaryDir() + "rslam-" + service, args, child));
}

void ServicePipeline::StartCamera(const CameraOptions& camera) {
  std::vector<std::string> args{"--domain", std::to_string(domain_), "--config", options_.config_file,
                                "--dds", camera.vendor.empty() ? "cyclone" : camera.vendor};
  for (const std::string& kv : std::vector<std::string>{"source=images", "path=" + camera.folder, "fps=" + std::to_string(camera.fps),
        "rate_hz=" + std::to_string(camera.rate_hz), "wait_for_readers=" + std::to_string(camera.readers),
        "wait_for_services=[odometry, templates]"}) {
    args.push_back("--set");
    args.push_back("camera." + kv);
  }
  testing::ChildProcess::Options child;
  if (!options_.log_dir.empty()) child.log_file = options_.log_dir + "/camera.log";
  camera_ = std::make_unique<testing::ChildProcess>(BinaryDir() + "rslam-camera", args, child);
}

bool ServicePipeline::WaitForFrames(std::size_t frames, std::chrono::milliseconds timeout) {
  return testing::WaitFor(
      [&] {
        std::lock_guard lock(mutex_);
        return poses_.size() >= frames && latest_map_ && latest_map_->action_seq == poses_.back().action_seq;
      },
      timeout);
}

std::optional<int> ServicePipeline::WaitCameraExit(std::chrono::milliseconds timeout) {
  if (!camera_) return std::nullopt;
  return camera_->WaitExit(timeout);
}

std::string ServicePipeline::StopServices() {
  std::string problems;
  for (auto& service : services_) {
    const int code = service->Stop(std::chrono::milliseconds(10000));
    if (code != 0) problems += service->name() + " exited " + std::to_string(code) + "\n" + service->Tail();
  }
  return problems;
}

std::vector<msg::ExperiencePose> ServicePipeline::Poses() {
  std::lock_guard lock(mutex_);
  return poses_;
}

std::optional<msg::ExperienceMap> ServicePipeline::LatestMap() {
  std::lock_guard lock(mutex_);
  return latest_map_;
}

std::string ServicePipeline::Logs() const {
  std::string text;
  if (camera_) text += camera_->Tail(2000);
  for (const auto& s : services_) text += s->Tail(2000);
  return text;
}

}  // namespace rslam::system_test
