// IndependentReader: a recording of real rslam message types made on the bus is read with the
// official Foxglove MCAP packages and every message decoded from its CDR with the IDL schema
// stored in the file (decode_recording.mjs); counts and every decoded field must equal what was
// published. Skips only where node/npm are absent.
#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>

#include "common/bus/publisher.h"
#include "common/bus/topics.h"
#include "common/mcap/mcap_crc32.h"
#include "tests/integration/record/record_test_util.h"
#include "tests/support/test_domain.h"
#include "tools/record/recorder.h"

namespace rslam::record {
namespace {

using namespace testing;
using nlohmann::json;

bool HaveCommand(const std::string& name) {
  return std::system(("command -v " + name + " > /dev/null 2>&1").c_str()) == 0;
}

std::string RunShell(const std::string& command, int& status) {
  std::string out;
  FILE* p = ::popen(command.c_str(), "r");
  if (p == nullptr) {
    status = -1;
    return out;
  }
  char buf[65536];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof(buf), p)) > 0) out.append(buf, n);
  status = ::pclose(p);
  return out;
}

// The npm packages, installed once per build tree.
std::string NodeModulesDir() {
  const std::string prefix = std::string(RSLAM_BINARY_DIR) + "/npm-record";
  const std::string modules = prefix + "/node_modules";
  std::string missing;
  for (const char* p : {"@mcap/core", "@mcap/nodejs", "@mcap/support", "@foxglove/omgidl-parser",
                        "@foxglove/omgidl-serialization"})
    if (!fs::exists(modules + "/" + p)) missing += std::string(" ") + p;
  if (!missing.empty()) {
    int status = 0;
    const std::string log =
        RunShell("npm install --no-audit --no-fund --silent --prefix '" + prefix + "'" + missing + " 2>&1", status);
    if (status != 0) ADD_FAILURE() << "npm install failed:\n" << log;
  }
  return modules;
}

// The decoded form the script prints: 64-bit integers as strings, enums as numbers, byte
// sequences as {length, crc32}.
json Bytes(const std::vector<uint8_t>& v) { return {{"length", v.size()}, {"crc32", mcap::Crc32(v.data(), v.size())}}; }
json ToJson(const msg::Header& h) {
  return {{"robot_id", h.robot_id}, {"frame_seq", std::to_string(h.frame_seq)}, {"stamp_ns", std::to_string(h.stamp_ns)}};
}
json ToJson(const msg::Image& m) {
  return {{"header", ToJson(m.header)}, {"width", m.width},       {"height", m.height},
          {"encoding", m.encoding},     {"step", m.step},         {"data", Bytes(m.data)}};
}
json ToJson(const std::vector<msg::FloorPoint>& points) {
  json boundary = json::array();
  for (const auto& p : points) boundary.push_back({{"x_m", static_cast<double>(p.x_m)}, {"y_m", static_cast<double>(p.y_m)}});
  return boundary;
}
json ToJson(const msg::Velocity& m) {
  return {{"header", ToJson(m.header)},
          {"vtrans_mps", m.vtrans_mps},
          {"vrot_radps", m.vrot_radps},
          {"dt_s", m.dt_s},
          {"source", static_cast<int>(m.source)},
          {"wall_seen", m.wall_seen},
          {"wall_direction_rad", m.wall_direction_rad},
          {"boundary_measured", m.boundary_measured},
          {"boundary", ToJson(m.boundary)}};
}
json ToJson(const msg::PoseCellAction& m) {
  return {{"header", ToJson(m.header)},
          {"action_seq", std::to_string(m.action_seq)},
          {"kind", static_cast<int>(m.kind)},
          {"experience_id", m.experience_id},
          {"from_experience_id", m.from_experience_id},
          {"template_id", m.template_id},
          {"relative_angle_rad", m.relative_angle_rad},
          {"offset_x_m", m.offset_x_m},
          {"offset_y_m", m.offset_y_m},
          {"pc_x", static_cast<double>(m.pc_x)},
          {"pc_y", static_cast<double>(m.pc_y)},
          {"pc_th", static_cast<double>(m.pc_th)},
          {"vtrans_mps", m.vtrans_mps},
          {"vrot_radps", m.vrot_radps},
          {"dt_s", m.dt_s},
          {"wall_seen", m.wall_seen},
          {"wall_direction_rad", m.wall_direction_rad},
          {"boundary_measured", m.boundary_measured},
          {"boundary", ToJson(m.boundary)}};
}
json ToJson(const msg::ExperienceMap& m) {
  json experiences = json::array();
  for (const auto& e : m.experiences)
    experiences.push_back({{"id", e.id}, {"x_m", e.x_m}, {"y_m", e.y_m}, {"theta_rad", e.theta_rad},
                           {"template_id", e.template_id}, {"pc_x", static_cast<double>(e.pc_x)},
                           {"pc_y", static_cast<double>(e.pc_y)}, {"pc_th", static_cast<double>(e.pc_th)}});
  json links = json::array();
  for (const auto& l : m.links)
    links.push_back({{"from_id", l.from_id}, {"to_id", l.to_id}, {"distance_m", l.distance_m},
                     {"heading_rad", l.heading_rad}, {"facing_rad", l.facing_rad},
                     {"travel_time_s", l.travel_time_s}, {"closes_loop", l.closes_loop}});
  return {{"header", ToJson(m.header)},
          {"map_version", std::to_string(m.map_version)},
          {"action_seq", std::to_string(m.action_seq)},
          {"current_experience_id", m.current_experience_id},
          {"experiences", experiences},
          {"links", links}};
}

TEST(IndependentReader, FoxgloveDecodesEveryRecordedMessageAsPublished) {
  if (!HaveCommand("node") || !HaveCommand("npm")) GTEST_SKIP() << "node/npm not installed";
  const std::string modules = NodeModulesDir();
  rslam::testing::TestDomain domain;
  const auto dir = ScratchFolderForTest();
  RecorderOptions options;
  options.file.path = (dir / "typed.mcap").string();
  options.topics_regex = "^(camera/image|odometry/velocity|pose_cells/action|experience_map/map)$";
  auto recorder_participant = MakeParticipant(domain.id(), "rslam-record");
  Recorder recorder(*recorder_participant, options);

  std::map<ChannelKey, std::vector<json>> expected;
  {
    struct Robot {
      Robot(bus::Participant& p)
          : images(p, bus::topics::kCameraImage),
            velocities(p, bus::topics::kOdometryVelocity),
            actions(p, bus::topics::kPoseCellsAction),
            maps(p, bus::topics::kExperienceMapMap) {}
      bus::Publisher<msg::Image> images;
      bus::Publisher<msg::Velocity> velocities;
      bus::Publisher<msg::PoseCellAction> actions;
      bus::Publisher<msg::ExperienceMap> maps;
    };
    const std::vector<std::string> names = {"robot1", "robot2"};
    std::vector<std::unique_ptr<bus::Participant>> participants;
    std::vector<std::unique_ptr<Robot>> robots;
    for (const auto& name : names) {
      participants.push_back(MakeParticipant(domain.id(), name));
      robots.push_back(std::make_unique<Robot>(*participants.back()));
    }
    for (auto& r : robots)
      ASSERT_TRUE(r->images.WaitForSubscribers(1, 15s) && r->velocities.WaitForSubscribers(1, 15s) &&
                  r->actions.WaitForSubscribers(1, 15s) && r->maps.WaitForSubscribers(1, 15s));
    const auto deadline = std::chrono::steady_clock::now() + 15s;
    for (bool all = false; !all;) {  // the recorder's side of the match too
      all = true;
      for (const auto& s : recorder.Subscriptions()) all = all && s.matched_writers >= 2;
      ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "recorder readers did not match both robots";
      if (!all) std::this_thread::sleep_for(10ms);  // DDS offers no wait on matching
    }
    for (std::size_t r = 0; r < robots.size(); ++r) {
      const std::string& robot = names[r];
      Robot& pub = *robots[r];
      for (int i = 0; i < 12; ++i) {
        msg::Velocity v;
        FillExample(v, i);
        v.header = {robot, static_cast<uint64_t>(i), 1'700'000'000'123'456'789 + i};
        v.vtrans_mps = 0.1 * i + 0.015625;
        v.vrot_radps = -0.3 / (i + 1);
        pub.velocities.Publish(v);
        expected[{"odometry/velocity", robot}].push_back(ToJson(v));
        msg::PoseCellAction a;
        FillExample(a, 3 * i);
        a.header = v.header;
        a.kind = static_cast<msg::ActionKind>(i % msg::kActionKindCount);
        a.pc_x = 0.5f + i;
        a.dt_s = 1.0 / 30;
        pub.actions.Publish(a);
        expected[{"pose_cells/action", robot}].push_back(ToJson(a));
        if (i % 4 == 0) {
          const msg::Image image = MakeImage(robot, i, 32, 24);
          pub.images.Publish(image);
          expected[{"camera/image", robot}].push_back(ToJson(image));
          ASSERT_TRUE(pub.images.WaitForAcknowledgments(10s));
        }
      }
      msg::ExperienceMap map;
      FillExample(map, static_cast<int>(r) + 1);
      map.header.robot_id = robot;
      map.experiences[1].x_m = -2.75;
      map.links[2].closes_loop = true;
      pub.maps.Publish(map);
      expected[{"experience_map/map", robot}].push_back(ToJson(map));
      ASSERT_TRUE(pub.velocities.WaitForAcknowledgments(10s) && pub.actions.WaitForAcknowledgments(10s) &&
                  pub.maps.WaitForAcknowledgments(10s));
    }
    recorder.Stop();
  }
  EXPECT_EQ(recorder.Stats().dropped, 0u);

  int status = 0;
  const std::string script = std::string(RSLAM_SOURCE_DIR) + "/tests/integration/record/decode_recording.mjs";
  const std::string out =
      RunShell("NODE_PATH='" + modules + "' node '" + script + "' '" + options.file.path + "' 2>&1", status);
  ASSERT_EQ(status, 0) << out;
  const json j = json::parse(out);

  std::size_t total = 0;
  for (const auto& [k, v] : expected) total += v.size();
  ASSERT_FALSE(j["statistics"].is_null());
  EXPECT_EQ(j["statistics"]["message_count"], total);
  ASSERT_EQ(j["messages"].size(), total);
  EXPECT_EQ(j["channels"].size(), expected.size());
  for (const auto& c : j["channels"]) {
    EXPECT_EQ(c["schema_encoding"], "omgidl");
    EXPECT_EQ(c["message_encoding"], "cdr");
  }

  std::map<ChannelKey, std::vector<std::pair<uint32_t, json>>> decoded;
  for (const auto& m : j["messages"])
    decoded[{m["dds_topic"], m["robot"]}].emplace_back(m["sequence"].get<uint32_t>(), m["decoded"]);
  ASSERT_EQ(decoded.size(), expected.size());
  for (auto& [key, list] : decoded) {
    SCOPED_TRACE(key.first + "@" + key.second);
    std::stable_sort(list.begin(), list.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const auto& want = expected.at(key);
    ASSERT_EQ(list.size(), want.size());
    for (std::size_t i = 0; i < list.size(); ++i) EXPECT_EQ(list[i].second, want[i]) << "message " << i;
  }
}

}  // namespace
}  // namespace rslam::record
