#include "common/bus/participant.h"

#include <algorithm>
#include <cstdlib>

namespace rslam::bus {

Vendor ParseVendor(const std::string& name, const std::string& key) {
  if (name == "cyclone") return Vendor::kCyclone;
  if (name == "fastdds") return Vendor::kFastDds;
  throw ConfigError(key, "unknown DDS vendor '" + name + "' (cyclone or fastdds)");
}

const char* VendorName(Vendor vendor) { return vendor == Vendor::kCyclone ? "cyclone" : "fastdds"; }

void BusConfig::Validate() const {
  ParseVendor(dds, "dds");
  // Ports are 7400 + 250 * domain + ...: above 229 they leave the 16-bit range.
  Require(domain_id >= 0 && domain_id <= 229, "domain_id", "must be 0-229, got " + std::to_string(domain_id));
  Require(!robot_id.empty(), "robot_id", "must not be empty");
  Require(robot_id.find_first_of("*?[]") == std::string::npos, "robot_id",
          "must not contain partition wildcards (* ? [ ])");
}

void BusConfig::ApplyEnvironment() {
  if (const char* env = std::getenv("RSLAM_DDS"); env != nullptr && *env != '\0') {
    ParseVendor(env, "RSLAM_DDS");
    dds = env;
  }
  if (const char* env = std::getenv("RSLAM_DOMAIN"); env != nullptr && *env != '\0') {
    char* end = nullptr;
    const long id = std::strtol(env, &end, 10);
    Require(end != env && *end == '\0', "RSLAM_DOMAIN", std::string("not an integer: '") + env + "'");
    domain_id = static_cast<int>(id);
  }
  Validate();
}

std::unique_ptr<Participant> Participant::Create(const BusConfig& config) {
  config.Validate();
  return config.vendor() == Vendor::kCyclone ? CreateCycloneParticipant(config) : CreateFastDdsParticipant(config);
}

void Participant::Track(const std::string& topic, const RawWriter* writer) {
  std::lock_guard lock(tracked_mutex_);
  tracked_.push_back({topic, writer, nullptr});
}

void Participant::Track(const std::string& topic, const RawReader* reader) {
  std::lock_guard lock(tracked_mutex_);
  tracked_.push_back({topic, nullptr, reader});
}

void Participant::Untrack(const void* endpoint) {
  std::lock_guard lock(tracked_mutex_);
  std::erase_if(tracked_, [endpoint](const Tracked& t) {
    return t.writer == endpoint || t.reader == endpoint;
  });
}

std::vector<EndpointMatchCount> Participant::Matches() const {
  std::lock_guard lock(tracked_mutex_);
  std::vector<EndpointMatchCount> out;
  out.reserve(tracked_.size());
  for (const Tracked& t : tracked_)
    out.push_back({t.topic, t.writer != nullptr, t.writer ? t.writer->MatchedReaders() : t.reader->MatchedWriters()});
  return out;
}

}  // namespace rslam::bus
