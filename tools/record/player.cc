#include "tools/record/player.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <regex>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <tuple>

#include "common/bus/cdr.h"
#include "common/bus/message_registry.h"
#include "common/mcap/mcap_reader.h"
#include "tools/record/recorded_topic.h"

namespace rslam::record {
namespace {

using Clock = std::chrono::steady_clock;

// Thrown inside McapReader::ForEachMessage to leave it when the stop token fires.
struct PlaybackStopped {};

struct Output {
  PlayedChannel info;
  const bus::MessageTypeInfo* type = nullptr;
  // At max speed: wait for acknowledgments after this many messages (0 = never: keep-all
  // writers get back-pressure instead). Every message for shallow keep-last histories (sensor,
  // state), so a reader's history never overflows; a quarter of a deep one (log).
  uint64_t ack_every = 0;
  uint64_t unacknowledged = 0;
  bool remap = false;
  std::unique_ptr<bus::RawWriter> writer;
};

struct FilePlan {
  std::unique_ptr<mcap::McapReader> reader;
  std::map<uint16_t, std::size_t> outputs;  // channel id -> index into the outputs
  std::set<std::string> topics;             // MCAP topics of those channels
};

const std::string* Find(const std::map<std::string, std::string>& m, const std::string& key) {
  auto it = m.find(key);
  return it == m.end() || it->second.empty() ? nullptr : &it->second;
}

void CheckOptions(const PlayOptions& o) {
  if (!o.max_speed && !(std::isfinite(o.rate) && o.rate > 0)) throw std::invalid_argument("--rate must be a positive number");
  if (!(o.start_s >= 0)) throw std::invalid_argument("--start must be >= 0 seconds");
  if (!(o.end_s >= o.start_s)) throw std::invalid_argument("--end must not be before --start");
  if (o.wait_for_readers < 0) throw std::invalid_argument("--wait-for-readers must be >= 0");
  for (const auto& [from, to] : o.robot_remap) {
    if (from.empty() || to.empty() || to.find_first_of("*?[]") != std::string::npos)
      throw std::invalid_argument("--robot-remap: '" + from + "=" + to + "' is not ROBOT=ROBOT");
  }
}

// Sleeps until deadline; throws PlaybackStopped when the stop token fires first.
void SleepUntil(Clock::time_point deadline, std::stop_token stop) {
  std::mutex mutex;
  std::condition_variable_any cv;
  std::unique_lock lock(mutex);
  cv.wait_until(lock, stop, deadline, [] { return false; });
  if (stop.stop_requested()) throw PlaybackStopped{};
}

uint64_t SecondsToNs(double s) {
  if (!std::isfinite(s) || s * 1e9 >= 1.8e19) return UINT64_MAX;
  return static_cast<uint64_t>(std::llround(s * 1e9));
}

void Notify(const PlayOptions& o, const std::string& text) {
  if (o.on_event) o.on_event(text);
}

// Waits until every writer has options.wait_for_readers matched readers; false on timeout.
bool WaitForReaders(const std::vector<Output>& outputs, const PlayOptions& o, std::stop_token stop) {
  if (o.wait_for_readers == 0) return true;
  const auto deadline = Clock::now() + o.wait_timeout;
  while (true) {
    bool all = true;
    for (const auto& out : outputs) all = all && out.writer->MatchedReaders() >= o.wait_for_readers;
    if (all) return true;
    if (Clock::now() >= deadline) break;
    SleepUntil(Clock::now() + std::chrono::milliseconds(10), stop);  // DDS offers no wait on matching
  }
  std::string missing;
  for (const auto& out : outputs)
    if (out.writer->MatchedReaders() < o.wait_for_readers)
      missing += " " + out.info.dds_topic + "@" + out.info.partition;
  Notify(o, "no reader matched within " + std::to_string(o.wait_timeout.count()) + " ms for:" + missing +
                "; playing anyway");
  return false;
}

}  // namespace

std::pair<std::string, std::string> ParseRobotRemap(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size() || text.find('=', eq + 1) != std::string::npos)
    throw std::invalid_argument("--robot-remap: expected FROM=TO, got '" + text + "'");
  return {text.substr(0, eq), text.substr(eq + 1)};
}

PlayReport PlayFile(bus::Participant& participant, const std::string& path, const PlayOptions& options,
                    std::stop_token stop) {
  return PlayFiles(participant, std::vector<std::string>{path}, options, stop);
}

PlayReport PlayFiles(bus::Participant& participant, const std::vector<std::string>& paths, const PlayOptions& options,
                     std::stop_token stop) {
  CheckOptions(options);
  if (paths.empty()) throw std::invalid_argument("no recording to play");
  std::regex topic_filter;
  try {
    topic_filter = std::regex(options.topics_regex, std::regex::ECMAScript);
  } catch (const std::regex_error& e) {
    throw std::invalid_argument("--topics: bad regular expression '" + options.topics_regex + "': " + e.what());
  }

  // Validate every file before publishing anything.
  std::vector<FilePlan> files;
  uint64_t origin = UINT64_MAX;
  for (const auto& path : paths) {
    FilePlan plan;
    plan.reader = std::make_unique<mcap::McapReader>(path);
    if (plan.reader->statistics().message_count > 0)
      origin = std::min(origin, plan.reader->statistics().message_start_time);
    files.push_back(std::move(plan));
  }

  PlayReport report;
  std::vector<Output> outputs;
  std::map<std::tuple<std::string, std::string, std::string>, std::size_t> output_by_key;
  std::set<std::string> skipped;
  for (auto& file : files) {
    const auto& schemas = file.reader->schemas();
    for (const auto& [id, channel] : file.reader->channels()) {
      std::string why;
      const bus::MessageTypeInfo* type = nullptr;
      const std::string* dds_topic = Find(channel.metadata, mcap::kMetadataDdsTopic);
      const std::string* robot = Find(channel.metadata, mcap::kMetadataRobot);
      const std::string* qos_name = Find(channel.metadata, mcap::kMetadataQos);
      auto schema = schemas.find(channel.schema_id);
      bus::QosPreset qos = bus::QosPreset::kStream;
      if (channel.message_encoding != mcap::kMessageEncodingCdr) {
        why = "message encoding '" + channel.message_encoding + "' is not cdr";
      } else if (schema == schemas.end() || schema->second.encoding != mcap::kSchemaEncodingOmgIdl) {
        why = "no omgidl schema";
      } else if ((type = bus::FindMessageType(schema->second.name)) == nullptr) {
        why = "unknown type " + schema->second.name;
      } else if (!bus::SameIdlDefinition(schema->second.data, type->idl)) {
        // Recorded by another version of rslam whose message differs: today's readers would
        // refuse every sample as malformed.
        why = "recorded with another definition of " + schema->second.name + " than this build's";
      } else if (dds_topic == nullptr || robot == nullptr || qos_name == nullptr) {
        why = "metadata lacks dds_topic, robot or qos";
      } else {
        try {
          qos = bus::ParseQosPreset(*qos_name);
        } catch (const std::invalid_argument& e) {
          why = e.what();
        }
      }
      if (!why.empty()) {
        if (skipped.insert(channel.topic + ": " + why).second) {
          report.skipped_channels.push_back(channel.topic + ": " + why);
          Notify(options, "skipping channel " + channel.topic + ": " + why);
        }
        continue;
      }
      if (!options.topics_regex.empty() && !std::regex_search(*dds_topic, topic_filter)) continue;

      const auto key = std::make_tuple(*dds_topic, *robot, std::string(type->type_name));
      auto it = output_by_key.find(key);
      if (it == output_by_key.end()) {
        Output out;
        const auto remap = options.robot_remap.find(*robot);
        out.remap = remap != options.robot_remap.end();
        out.info = PlayedChannel{*dds_topic, type->type_name, *qos_name, *robot, out.remap ? remap->second : *robot, 0};
        out.type = type;
        const bus::QosSettings settings = bus::SettingsOf(qos);
        out.ack_every = settings.keep_all ? 0 : settings.depth >= 1000 ? static_cast<uint64_t>(settings.depth / 4) : 1;
        out.writer = participant.CreateRawWriter(
            bus::TopicSpec{*dds_topic, type->type_name, type->key_reader, qos, out.info.partition});
        it = output_by_key.emplace(key, outputs.size()).first;
        outputs.push_back(std::move(out));
      }
      file.outputs[id] = it->second;
      file.topics.insert(channel.topic);
    }
  }
  if (outputs.empty()) {
    Notify(options, "nothing to play");
    return report;
  }

  try {
    report.readers_matched = WaitForReaders(outputs, options, stop);
    if (report.readers_matched && options.wait_for_readers > 0) SleepUntil(Clock::now() + options.settle, stop);

    const uint64_t window_start = origin == UINT64_MAX ? 0 : origin + SecondsToNs(options.start_s);
    const uint64_t end_offset = SecondsToNs(options.end_s);
    const uint64_t window_end = end_offset == UINT64_MAX || origin == UINT64_MAX ? UINT64_MAX : origin + end_offset;
    std::vector<uint8_t> remapped;
    do {
      const uint64_t published_before = report.messages;
      const auto wall_start = Clock::now();
      for (auto& file : files) {
        if (file.topics.empty()) continue;
        mcap::MessageFilter filter;
        filter.topics = file.topics;
        filter.start_time = window_start;
        filter.end_time = window_end;
        file.reader->ForEachMessage(filter, [&](const mcap::MessageView& m) {
          if (stop.stop_requested()) throw PlaybackStopped{};
          const auto it = file.outputs.find(m.channel->id);
          if (it == file.outputs.end()) return;
          Output& out = outputs[it->second];
          if (!options.max_speed) {
            const double offset_ns = static_cast<double>(m.log_time - window_start) / options.rate;
            SleepUntil(wall_start + std::chrono::nanoseconds(static_cast<int64_t>(offset_ns)), stop);
          }
          std::span<const uint8_t> cdr(reinterpret_cast<const uint8_t*>(m.data.data()), m.data.size());
          if (out.remap) {
            try {
              remapped = out.type->with_robot_id(cdr, out.info.partition);
            } catch (const bus::CdrError&) {
              ++report.malformed;
              return;
            }
            cdr = remapped;
          }
          out.writer->Write(cdr);
          if (options.max_speed && out.ack_every > 0 && ++out.unacknowledged >= out.ack_every) {
            out.unacknowledged = 0;
            if (!out.writer->WaitForAcknowledgments(options.ack_timeout)) ++report.ack_timeouts;
          }
          ++out.info.messages;
          ++report.messages;
        });
      }
      ++report.loops;
      if (report.messages == published_before) break;  // an empty window would loop forever
    } while (options.loop && !stop.stop_requested());
    report.stopped = stop.stop_requested();  // a stop between two passes ends the loop here
  } catch (const PlaybackStopped&) {
    report.stopped = true;
  }
  // Deliver the tail before the writers go away (briefly when interrupted: the user wants out).
  const auto tail = report.stopped ? std::min(options.ack_timeout, std::chrono::milliseconds(1000)) : options.ack_timeout;
  for (auto& out : outputs) out.writer->WaitForAcknowledgments(tail);
  for (const auto& out : outputs) report.channels.push_back(out.info);
  return report;
}

}  // namespace rslam::record
