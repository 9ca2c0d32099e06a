#include "tools/record/recording_info.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

#include "common/mcap/mcap_reader.h"

namespace rslam::record {
namespace {

std::string MetadataOf(const mcap::Channel& c, const char* key) {
  auto it = c.metadata.find(key);
  return it == c.metadata.end() ? std::string() : it->second;
}

std::string HumanBytes(uint64_t n) {
  char buf[32];
  if (n >= (uint64_t{1} << 30)) std::snprintf(buf, sizeof(buf), "%.2f GiB", n / double(uint64_t{1} << 30));
  else if (n >= (uint64_t{1} << 20)) std::snprintf(buf, sizeof(buf), "%.2f MiB", n / double(uint64_t{1} << 20));
  else if (n >= 1024) std::snprintf(buf, sizeof(buf), "%.1f KiB", n / 1024.0);
  else std::snprintf(buf, sizeof(buf), "%llu B", static_cast<unsigned long long>(n));
  return buf;
}

// (dds topic or MCAP topic, type) -> total count, in first-seen order of channel ids.
std::vector<std::tuple<std::string, std::string, uint64_t>> TopicTotals(const RecordingInfo& info) {
  std::vector<std::tuple<std::string, std::string, uint64_t>> out;
  for (const auto& c : info.channels) {
    const std::string& name = c.dds_topic.empty() ? c.topic : c.dds_topic;
    auto it = std::find_if(out.begin(), out.end(), [&](const auto& t) {
      return std::get<0>(t) == name && std::get<1>(t) == c.type;
    });
    if (it == out.end()) out.emplace_back(name, c.type, c.message_count);
    else std::get<2>(*it) += c.message_count;
  }
  return out;
}

}  // namespace

RecordingInfo DescribeRecording(const std::string& path) {
  const mcap::McapReader reader(path);
  RecordingInfo info;
  info.path = path;
  info.size_bytes = reader.file_size();
  info.profile = reader.profile();
  info.library = reader.library();
  std::set<std::string> compressions;
  for (const auto& c : reader.chunks()) compressions.insert(c.compression.empty() ? "none" : c.compression);
  info.compressions.assign(compressions.begin(), compressions.end());
  const auto& st = reader.statistics();
  info.chunk_count = reader.chunks().size();
  info.message_count = st.message_count;
  info.start_time_ns = st.message_start_time;
  info.end_time_ns = st.message_end_time;
  std::set<std::string> robots;
  for (const auto& [id, c] : reader.channels()) {
    ChannelInfo ci;
    ci.id = id;
    ci.topic = c.topic;
    ci.dds_topic = MetadataOf(c, mcap::kMetadataDdsTopic);
    auto schema = reader.schemas().find(c.schema_id);
    ci.type = schema == reader.schemas().end() ? std::string() : schema->second.name;
    ci.robot = MetadataOf(c, mcap::kMetadataRobot);
    ci.qos = MetadataOf(c, mcap::kMetadataQos);
    ci.dds_vendor = MetadataOf(c, mcap::kMetadataDdsVendor);
    auto count = st.channel_message_counts.find(id);
    ci.message_count = count == st.channel_message_counts.end() ? 0 : count->second;
    if (!ci.robot.empty()) robots.insert(ci.robot);
    info.channels.push_back(std::move(ci));
  }
  info.robots.assign(robots.begin(), robots.end());
  return info;
}

nlohmann::json ToJson(const RecordingInfo& info) {
  nlohmann::json j;
  j["path"] = info.path;
  j["size_bytes"] = info.size_bytes;
  j["profile"] = info.profile;
  j["library"] = info.library;
  j["compression"] = info.compressions;
  j["chunk_count"] = info.chunk_count;
  j["message_count"] = info.message_count;
  j["start_time_ns"] = info.start_time_ns;
  j["end_time_ns"] = info.end_time_ns;
  j["duration_s"] = info.duration_s();
  j["robots"] = info.robots;
  j["topics"] = nlohmann::json::array();
  for (const auto& [topic, type, count] : TopicTotals(info))
    j["topics"].push_back({{"topic", topic}, {"type", type}, {"message_count", count}});
  j["channels"] = nlohmann::json::array();
  for (const auto& c : info.channels) {
    j["channels"].push_back({{"id", c.id}, {"topic", c.topic}, {"dds_topic", c.dds_topic}, {"type", c.type},
                             {"robot", c.robot}, {"qos", c.qos}, {"dds_vendor", c.dds_vendor},
                             {"message_count", c.message_count}});
  }
  return j;
}

std::string FormatRecordingInfo(const RecordingInfo& info) {
  std::ostringstream out;
  char line[512];
  auto join = [](const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s.empty() ? std::string("-") : s;
  };
  std::snprintf(line, sizeof(line), "%-13s%s\n", "File:", info.path.c_str());
  out << line;
  std::snprintf(line, sizeof(line), "%-13s%s\n", "Size:", HumanBytes(info.size_bytes).c_str());
  out << line;
  std::snprintf(line, sizeof(line), "%-13s%s (%llu chunks)\n", "Compression:", join(info.compressions).c_str(),
                static_cast<unsigned long long>(info.chunk_count));
  out << line;
  std::snprintf(line, sizeof(line), "%-13s%.3f s\n", "Duration:", info.duration_s());
  out << line;
  std::snprintf(line, sizeof(line), "%-13s%llu\n", "Messages:", static_cast<unsigned long long>(info.message_count));
  out << line;
  std::snprintf(line, sizeof(line), "%-13s%s\n", "Robots:", join(info.robots).c_str());
  out << line;
  std::snprintf(line, sizeof(line), "%-13s%s%s%s\n", "Library:", info.library.c_str(),
                info.profile.empty() ? "" : ", profile ", info.profile.c_str());
  out << line;
  out << "Channels:\n";
  for (const auto& c : info.channels) {
    std::snprintf(line, sizeof(line), "  %-36s %-28s %-7s %10llu msgs  (robot %s, %s)\n", c.topic.c_str(),
                  c.type.c_str(), c.qos.c_str(), static_cast<unsigned long long>(c.message_count),
                  c.robot.empty() ? "-" : c.robot.c_str(), c.dds_vendor.empty() ? "-" : c.dds_vendor.c_str());
    out << line;
  }
  out << "Topics:\n";
  for (const auto& [topic, type, count] : TopicTotals(info)) {
    std::snprintf(line, sizeof(line), "  %-36s %-28s %10llu msgs\n", topic.c_str(), type.c_str(),
                  static_cast<unsigned long long>(count));
    out << line;
  }
  return out.str();
}

}  // namespace rslam::record
