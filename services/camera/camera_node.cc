#include "services/camera/camera_node.h"

#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "common/node/frame_pacer.h"
#include "common/node/heartbeat.h"
#include "common/node/shutdown_signal.h"
#include "services/camera/frame_preparation.h"
#include "services/camera/frame_source.h"
#include "services/camera/image_message.h"

namespace rslam::camera {

using Clock = std::chrono::steady_clock;

class CameraNode::Impl {
 public:
  Impl(ServiceContext& context, const Config& config)
      : context_(context),
        config_(config),
        preparation_(config),
        live_(config.source == "device"),
        lockstep_(config.source != "sim" && config.source != "device" && config.rate_hz == 0 &&
                  !config.lockstep_topics.empty()),
        pacer_(static_cast<int>(config.lockstep_topics.size()), config.max_frames_in_flight,
               Seconds(config.lockstep_timeout_s), Seconds(config.lockstep_startup_timeout_s)) {}

  ~Impl() { Stop(); }

  void Start(std::vector<std::shared_ptr<void>>& subscriptions) {
    publisher_ = context_.Advertise(bus::topics::kCameraImage);
    if (config_.source == "sim") {
      // The callback holds only a weak reference: the subscriber outlives the node.
      std::weak_ptr<Impl> weak = self_;
      subscriptions.push_back(context_.Subscribe<msg::Image>(bus::topics::kSimCamera, [weak](const msg::Image& frame) {
        if (auto self = weak.lock()) self->OnSimFrame(frame);
      }));
      spdlog::info("republishing {} as {}", bus::topics::kSimCamera.name, bus::topics::kCameraImage.name);
      return;
    }
    if (lockstep_) SubscribeLockstepTopics(subscriptions);
    source_ = OpenSource();
    spdlog::info("source: {}", source_->Describe());
    // The first frame is read and prepared here, so a source or crop that cannot work fails the
    // start (exit 1, or exit 2 for a crop outside the frame) instead of a thread later.
    first_ = source_->Next();
    if (!first_) throw std::runtime_error(source_->Describe() + ": no frames");
    try {
      (void)preparation_.Apply(first_->image);
    } catch (const std::invalid_argument& e) {
      throw ConfigError(config_.crop.active() ? "crop" : "model", e.what());
    }
    thread_ = std::thread([this] { Run(); });
  }

  void Stop() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

  void set_self(const std::shared_ptr<Impl>& self) { self_ = self; }

 private:
  static Clock::duration Seconds(double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  }

  void SubscribeLockstepTopics(std::vector<std::shared_ptr<void>>& subscriptions) {
    namespace t = bus::topics;
    std::weak_ptr<Impl> weak = self_;
    for (std::size_t i = 0; i < config_.lockstep_topics.size(); ++i) {
      const std::string& name = config_.lockstep_topics[i];
      auto report = [weak, stage = static_cast<int>(i)](const auto& msg) {
        if (auto self = weak.lock()) self->Report(stage, msg.header.frame_seq);
      };
      if (name == t::kOdometryVelocity.name) {
        subscriptions.push_back(context_.Subscribe<msg::Velocity>(t::kOdometryVelocity, report));
      } else if (name == t::kTemplatesView.name) {
        subscriptions.push_back(context_.Subscribe<msg::ViewTemplate>(t::kTemplatesView, report));
      } else if (name == t::kPoseCellsAction.name) {
        subscriptions.push_back(context_.Subscribe<msg::PoseCellAction>(t::kPoseCellsAction, report));
      } else if (name == t::kExperienceMapPose.name) {
        subscriptions.push_back(context_.Subscribe<msg::ExperiencePose>(t::kExperienceMapPose, report));
      } else if (name == t::kOccupancyProfile.name) {
        subscriptions.push_back(context_.Subscribe<msg::ObstacleProfile>(t::kOccupancyProfile, report));
      } else {
        throw ConfigError("lockstep_topics", "unknown per-frame topic '" + name + "'");
      }
    }
    spdlog::info("lockstep with {} ({} frames in flight)", fmt::join(config_.lockstep_topics, ", "),
                 config_.max_frames_in_flight);
  }

  void Report(int stage, uint64_t frame_seq) {
    {
      std::lock_guard lock(mutex_);
      pacer_.Report(stage, frame_seq, Clock::now());
    }
    wake_.notify_all();
  }

  // rate_hz 0 with lockstep topics: waits until the pipeline is close enough behind frame_seq.
  // Returns false when stopped.
  bool AwaitPipeline(uint64_t frame_seq) {
    std::unique_lock lock(mutex_);
    while (!stop_ && !pacer_.MayPublish(frame_seq, Clock::now())) {
      // Timeouts of silent stages pass without a report: look again now and then.
      wake_.wait_for(lock, std::chrono::milliseconds(50));
    }
    return !stop_;
  }

  void PacerStarted() {
    std::lock_guard lock(mutex_);
    pacer_.Start(Clock::now());
  }

  std::unique_ptr<FrameSource> OpenSource() const {
    if (config_.source == "images") return OpenImageSequence(config_.path, config_.fps, config_.start_stamp_ns);
    if (config_.source == "video") return OpenVideoFile(config_.path);
    return OpenDevice(config_.device, config_.width, config_.height, config_.fps);
  }

  // Sleeps until `until` or Stop(); returns false when stopped.
  bool SleepUntil(Clock::time_point until) {
    std::unique_lock lock(mutex_);
    wake_.wait_until(lock, until, [this] { return stop_; });
    return !stop_;
  }

  bool stopped() {
    std::lock_guard lock(mutex_);
    return stop_;
  }

  // Recorded sources: before the first frame, wait for wait_for_readers readers of camera/image,
  // for heartbeats from wait_for_services, and for the heartbeats to show every link among the
  // services matched at both ends (a sample written before its reader matched is never
  // delivered; across vendors discovery takes a second). Then start anyway, saying what is missing.
  void WaitForReaders() {
    if (live_ || config_.wait_for_readers <= 0) return;
    const auto deadline = Clock::now() + Seconds(config_.wait_for_readers_timeout_s);
    const ServiceLinkWatch links(context_.participant());
    // With services named, the camera's own heartbeat must be among them, so that theirs are
    // checked against its writer: a writer-side match alone says nothing about the reader's side,
    // and a volatile reader drops what arrives before it knows the writer.
    std::vector<std::string> written;
    if (!config_.wait_for_services.empty()) written.emplace_back(bus::topics::kCameraImage.name);
    std::vector<std::string> missing;
    const auto ready = [&] {
      missing = links.Unmatched(config_.wait_for_services, written);
      return publisher_->MatchedSubscribers() >= config_.wait_for_readers && missing.empty();
    };
    while (!ready()) {
      if (Clock::now() >= deadline) {
        spdlog::warn("{} of {} readers after {} s; starting anyway{}{}", publisher_->MatchedSubscribers(),
                     config_.wait_for_readers, config_.wait_for_readers_timeout_s, missing.empty() ? "" : ": ",
                     fmt::join(missing, "; "));
        return;
      }
      if (!SleepUntil(Clock::now() + std::chrono::milliseconds(20))) return;  // DDS has no wait on matching
    }
  }

  // rate_hz 0: the next frame goes out once every matched reader has this one.
  void AwaitAcknowledgments() {
    const auto deadline =
        Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(config_.ack_timeout_s));
    while (!publisher_->WaitForAcknowledgments(std::chrono::milliseconds(100))) {
      if (stopped()) return;
      if (Clock::now() >= deadline) {
        if (!ack_timeout_logged_) {
          spdlog::warn("a reader did not acknowledge a frame within {} s; not waiting for it (logged once)",
                       config_.ack_timeout_s);
          ack_timeout_logged_ = true;
        }
        return;
      }
    }
  }

  void Run() {
    WaitForReaders();
    const auto period = config_.rate_hz > 0 ? std::chrono::duration_cast<Clock::duration>(
                                                  std::chrono::duration<double>(1.0 / config_.rate_hz))
                                            : Clock::duration::zero();
    const auto started = Clock::now();
    const int64_t nominal_period_ns = static_cast<int64_t>(1e9 / config_.fps);
    uint64_t seq_offset = 0;
    // A looped source's stamps go on from the last one published: each frame's is shifted by
    // stamp_shift (0 until the first loop), set from the first frame read after each loop.
    bool shift_pending = false;
    int64_t next_stamp = 0, stamp_shift = 0;
    uint64_t published = 0;
    std::optional<Frame> frame = std::move(first_);
    while (!stopped()) {
      if (!frame) {
        try {
          frame = source_->Next();
        } catch (const std::runtime_error& e) {
          if (live_) return DeviceFailed(e.what());
          context_.Reject("unreadable_frame", e.what());
          continue;
        }
        if (!frame) {
          if (!config_.loop) {
            spdlog::info("end of {} after {} frames; stopping", source_->Describe(), published);
            RequestShutdown();
            return;
          }
          // Numbers and stamps continue upwards: consumers see one long run, never a jump back.
          seq_offset = last_seq_ + 1;
          shift_pending = true;
          next_stamp = last_stamp_ns_ + nominal_period_ns;
          source_ = OpenSource();
          spdlog::info("end of {}; looping (next frame {})", source_->Describe(), seq_offset);
          continue;
        }
        if (!live_) {
          if (shift_pending) stamp_shift = next_stamp - frame->stamp_ns;
          shift_pending = false;
          frame->stamp_ns += stamp_shift;
        }
        frame->seq += seq_offset;
      }
      if (period > Clock::duration::zero() && !live_ && !SleepUntil(started + period * static_cast<int64_t>(published)))
        return;
      if (lockstep_ && !AwaitPipeline(frame->seq)) return;
      cv::Mat prepared;
      try {
        prepared = preparation_.Apply(frame->image);
      } catch (const std::invalid_argument& e) {
        context_.Reject("unusable_frame", frame->name + ": " + e.what());
        frame.reset();
        continue;
      }
      Publish(prepared, frame->seq, frame->stamp_ns);
      if (published++ == 0 && lockstep_) PacerStarted();
      frame.reset();
      if (period == Clock::duration::zero() && !live_) AwaitAcknowledgments();
    }
  }

  [[noreturn]] void DeviceFailed(const std::string& reason) {
    spdlog::critical("{}; exiting so that a supervisor can restart the camera", reason);
    spdlog::default_logger()->flush();
    std::_Exit(1);
  }

  void Publish(const cv::Mat& image, uint64_t seq, int64_t stamp_ns) {
    message_.header = {context_.robot_id(), seq, stamp_ns};
    FillImageMessage(image, message_);
    PublishMessage(message_);
    context_.SetLastFrame(seq, stamp_ns);
    last_seq_ = seq;
    last_stamp_ns_ = stamp_ns;
  }

  // A reliable reader blocked beyond the sensor preset's limit makes Publish throw: that reader
  // misses this frame (counted, logged once); the camera goes on.
  void PublishMessage(const msg::Image& image) {
    try {
      publisher_->Publish(image);
    } catch (const bus::BusError& e) {
      context_.Reject("frame_not_delivered", e.what());
    }
  }

  void OnSimFrame(const msg::Image& frame) {
    if (stopped()) return;
    const std::string problem = ImageMessageProblem(frame, static_cast<uint64_t>(config_.max_pixels));
    if (!problem.empty()) return context_.Reject("malformed_image", problem);
    if (preparation_.identity()) {
      msg::Image out = frame;
      out.header.robot_id = context_.robot_id();
      PublishMessage(out);
      context_.SetLastFrame(out.header.frame_seq, out.header.stamp_ns);
      return;
    }
    cv::Mat prepared;
    try {
      prepared = preparation_.Apply(ImageView(frame));
    } catch (const std::invalid_argument& e) {
      return context_.Reject("unusable_frame", e.what());
    }
    std::lock_guard lock(sim_mutex_);
    Publish(prepared, frame.header.frame_seq, frame.header.stamp_ns);
  }

  ServiceContext& context_;
  const Config config_;
  const FramePreparation preparation_;
  const bool live_;
  const bool lockstep_;
  FramePacer pacer_;  // guarded by mutex_
  std::weak_ptr<Impl> self_;
  std::shared_ptr<bus::Publisher<msg::Image>> publisher_;
  std::unique_ptr<FrameSource> source_;
  std::optional<Frame> first_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  bool ack_timeout_logged_ = false;
  std::mutex sim_mutex_;  // guards message_ against overlapping sim callbacks (one thread, but cheap)
  msg::Image message_;
  uint64_t last_seq_ = 0;
  int64_t last_stamp_ns_ = 0;
};

CameraNode::CameraNode(ServiceContext& context, const Config& config) : impl_(std::make_shared<Impl>(context, config)) {
  impl_->set_self(impl_);
  impl_->Start(subscriptions_);
}

CameraNode::~CameraNode() {
  impl_->Stop();
  subscriptions_.clear();  // joins the callback threads while the node is whole
}

}  // namespace rslam::camera
