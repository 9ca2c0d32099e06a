#pragma once
// The RatSLAM services as separate processes on one test domain, and what the experience map
// publishes: rslam-experience-map, rslam-pose-cells, rslam-odometry and rslam-templates started
// (back to front, each awaited by its `running` heartbeat, so no frame reaches a stage before
// its next stage listens), then a frame source (rslam-camera on an image folder, or anything
// else that publishes camera/image on the domain). Every child is ended with the object.
//
// Observed from the test process: every experience_map/pose (one per applied action) and the
// newest experience_map/map snapshot.

#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/bus/participant.h"
#include "common/bus/subscriber.h"
#include "tests/support/child_process.h"

namespace rslam::system_test {

// Where the service binaries are: $RSLAM_SYSTEM_TEST_BIN_DIR when set (to test another build's
// binaries), else this build's bin folder.
std::string BinaryDir();

struct PipelineOptions {
  std::string config_file;                     // YAML with the four sections (and optionally more)
  std::map<std::string, std::string> vendors;  // service ("pose-cells") -> "fastdds"; default cyclone
  std::string log_dir;                         // service logs: <log_dir>/<service>.log
  std::chrono::milliseconds startup_timeout{20000};
};

struct CameraOptions {
  std::string folder;       // the images
  double fps = 10.0;        // stamps: frame i at i / fps s
  double rate_hz = 0.0;     // 0 = acknowledgment + lockstep pacing (as fast as the stages go)
  std::string vendor;       // "" = cyclone
  int readers = 2;          // camera/image readers to wait for (odometry, templates, + a recorder)
};

class ServicePipeline {
 public:
  // Starts the four services on domain and waits for their heartbeats. Throws std::runtime_error
  // (with the logs) when one does not come up in time.
  ServicePipeline(int domain, PipelineOptions options);
  ~ServicePipeline();
  ServicePipeline(const ServicePipeline&) = delete;
  ServicePipeline& operator=(const ServicePipeline&) = delete;

  // Starts rslam-camera on an image folder (it exits 0 after the last frame).
  void StartCamera(const CameraOptions& camera);
  // Waits until `frames` poses arrived and the newest snapshot reflects the last of them.
  bool WaitForFrames(std::size_t frames, std::chrono::milliseconds timeout);
  // The camera's exit code once it ended (nothing while it runs at the timeout).
  std::optional<int> WaitCameraExit(std::chrono::milliseconds timeout);
  // SIGTERM to every service; returns "" when all exited 0, else who did not.
  std::string StopServices();

  std::vector<msg::ExperiencePose> Poses();
  std::optional<msg::ExperienceMap> LatestMap();
  // The tails of every child's log, for failure messages.
  std::string Logs() const;
  int domain() const { return domain_; }

 private:
  std::vector<std::string> ServiceArgs(const std::string& service) const;
  void Start(const std::string& service, const std::vector<std::string>& extra_args = {});
  void AwaitDiscovery();

  const int domain_;
  const PipelineOptions options_;
  std::unique_ptr<bus::Participant> participant_;
  std::mutex mutex_;
  std::vector<msg::ExperiencePose> poses_;
  std::optional<msg::ExperienceMap> latest_map_;
  std::map<std::string, std::string> running_;  // service name in heartbeats -> state
  std::unique_ptr<bus::Subscriber<msg::ExperiencePose>> pose_subscriber_;
  std::unique_ptr<bus::Subscriber<msg::ExperienceMap>> map_subscriber_;
  std::unique_ptr<bus::Subscriber<msg::ServiceStatus>> status_subscriber_;
  std::vector<std::unique_ptr<testing::ChildProcess>> services_;  // started order
  std::unique_ptr<testing::ChildProcess> camera_;
};

}  // namespace rslam::system_test
