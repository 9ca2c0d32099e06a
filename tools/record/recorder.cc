#include "tools/record/recorder.h"

#include <deque>
#include <regex>
#include <stdexcept>

#include "common/bus/cdr.h"

namespace rslam::record {
namespace {

using namespace std::chrono_literals;

constexpr std::size_t kTakeBatch = 64;
constexpr const char* kAllRobots = "*";

std::regex Compile(const std::string& pattern, const std::string& what) {
  try {
    return std::regex(pattern, std::regex::ECMAScript);
  } catch (const std::regex_error& e) {
    throw std::invalid_argument(what + ": bad regular expression '" + pattern + "': " + e.what());
  }
}

std::vector<RecordedTopic> SelectTopics(const RecorderOptions& o) {
  const std::regex include = Compile(o.topics_regex, "--topics");
  const std::regex exclude = Compile(o.exclude_regex, "--exclude");
  std::vector<RecordedTopic> out;
  for (const auto& t : TopicTable()) {
    if (!o.topics_regex.empty() && !std::regex_search(t.name, include)) continue;
    if (!o.exclude_regex.empty() && std::regex_search(t.name, exclude)) continue;
    out.push_back(t);
  }
  if (out.empty()) throw std::invalid_argument("no topic of the topic table matches --topics/--exclude");
  return out;
}

// The recorder's reader QoS. Sensor topics are read keep-all: reliability and durability match
// the publishers' preset, and the history is the reader's own, so a burst of images waits in
// the reader cache instead of being overwritten before the reader thread takes it. State and log
// topics keep their preset (transient-local: the recorder gets the latest map, or the whole
// action log, at once).
bus::QosPreset ReaderPreset(bus::QosPreset published) {
  return published == bus::QosPreset::kSensor ? bus::QosPreset::kStream : published;
}

uint64_t NowNs() {
  return static_cast<uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count());
}

}  // namespace

std::string RobotIdOf(std::span<const uint8_t> cdr) {
  bus::CdrReader reader(cdr);
  std::string robot;
  reader.Read(robot);
  return robot;
}

Recorder::Recorder(bus::Participant& participant, const RecorderOptions& options)
    : options_(options), topics_(SelectTopics(options)), queue_(options.queue_bytes) {
  for (const auto& robot : options.robots) {
    if (robot.empty() || robot.find_first_of("*?[]") != std::string::npos)
      throw std::invalid_argument("--robot: '" + robot + "' is not a robot id");
  }
  writer_ = std::make_unique<RecordingWriter>(options.file, bus::VendorName(participant.vendor()));
  const std::vector<std::string> partitions =
      options.robots.empty() ? std::vector<std::string>{kAllRobots} : options.robots;
  for (std::size_t i = 0; i < topics_.size(); ++i) {
    for (const auto& partition : partitions) {
      auto s = std::make_unique<Subscription>();
      s->topic_index = i;
      s->partition = partition;
      s->reader = participant.CreateRawReader(bus::TopicSpec{topics_[i].name, topics_[i].type->type_name,
                                                             topics_[i].type->key_reader,
                                                             ReaderPreset(topics_[i].qos), partition});
      subscriptions_.push_back(std::move(s));
    }
  }
  writer_thread_ = std::thread([this] { WriteLoop(); });
  for (auto& s : subscriptions_) {
    Subscription* raw = s.get();
    s->thread = std::thread([this, raw] { ReadLoop(*raw); });
  }
}

Recorder::~Recorder() {
  try {
    Stop();
  } catch (...) {
    // The error was available from error() and Stop(); a destructor cannot report it.
  }
}

void Recorder::TakeAvailable(Subscription& s, std::vector<bus::RawSample>& batch) {
  while (true) {
    batch.clear();
    const std::size_t n = s.reader->Take(batch, kTakeBatch);
    if (n == 0) return;
    const uint64_t now = NowNs();
    received_ += n;
    for (auto& sample : batch) {
      ReceivedMessage m;
      m.topic_index = s.topic_index;
      if (s.partition != kAllRobots) {
        m.robot = s.partition;
      } else {
        try {
          m.robot = RobotIdOf(sample.cdr);
        } catch (const bus::CdrError&) {
          ++unattributed_;
          continue;
        }
        if (m.robot.empty()) {
          ++unattributed_;
          continue;
        }
      }
      m.cdr = std::move(sample.cdr);
      m.log_time_ns = now;
      m.publish_time_ns = sample.source_timestamp_ns > 0 ? static_cast<uint64_t>(sample.source_timestamp_ns) : 0;
      queue_.Push(std::move(m));
    }
    if (n < kTakeBatch) return;
  }
}

void Recorder::ReadLoop(Subscription& s) {
  std::vector<bus::RawSample> batch;
  batch.reserve(kTakeBatch);
  while (!stop_readers_) {
    s.reader->Wait(100ms);
    TakeAvailable(s, batch);
  }
  TakeAvailable(s, batch);  // what DDS delivered before the stop
}

void Recorder::WriteLoop() {
  std::deque<ReceivedMessage> batch;
  auto last_flush = std::chrono::steady_clock::now();
  bool failed = false;
  while (true) {
    // Read the flag before popping: once it is set, the readers have finished pushing.
    const bool finishing = stop_writer_;
    queue_.PopAll(batch, 50ms);
    if (!failed) {
      try {
        for (auto& m : batch) {
          writer_->Write(topics_[m.topic_index], m.robot, m.log_time_ns, m.publish_time_ns, m.cdr);
          ++written_;
        }
        channels_ = writer_->channel_count();
        const auto now = std::chrono::steady_clock::now();
        if (now - last_flush >= options_.flush_period) {
          writer_->Flush();
          last_flush = now;
        }
      } catch (...) {
        std::lock_guard lock(error_mutex_);
        error_ = std::current_exception();
        failed = true;
      }
    }
    if (finishing && batch.empty()) break;
  }
}

void Recorder::Stop() {
  if (stopped_) return;
  stopped_ = true;
  stop_readers_ = true;
  for (auto& s : subscriptions_) s->reader->Interrupt();
  for (auto& s : subscriptions_)
    if (s->thread.joinable()) s->thread.join();
  stop_writer_ = true;
  queue_.Wake();
  if (writer_thread_.joinable()) writer_thread_.join();
  // The readers stay until the recorder goes: nothing takes from them now, and deleting a DDS
  // reader can hang (Fast DDS 2.9.1, see ExitDeadline), which must not keep the file unfinished.
  {
    std::lock_guard lock(error_mutex_);
    if (error_) std::rethrow_exception(error_);
  }
  try {
    writer_->Close();
  } catch (...) {
    std::lock_guard lock(error_mutex_);
    error_ = std::current_exception();
    throw;
  }
}

std::vector<RecorderSubscription> Recorder::Subscriptions() const {
  std::vector<RecorderSubscription> out;
  for (const auto& s : subscriptions_)
    out.push_back({topics_[s->topic_index].name, s->partition, s->reader->MatchedWriters()});
  return out;
}

RecorderStats Recorder::Stats() const {
  RecorderStats st;
  st.received = received_;
  st.written = written_;
  st.dropped = queue_.dropped();
  st.unattributed = unattributed_;
  st.channels = channels_;
  st.queue_peak_bytes = queue_.peak_bytes();
  return st;
}

std::exception_ptr Recorder::error() const {
  std::lock_guard lock(error_mutex_);
  return error_;
}

std::vector<std::string> Recorder::paths() const { return writer_->paths(); }

}  // namespace rslam::record
