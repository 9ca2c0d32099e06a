// Files written by McapWriter read back identically with the official Foxglove readers
// (@mcap/core indexed + streaming readers, @mcap/support decompression) via read_mcap.mjs.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "common/mcap/mcap_crc32.h"
#include "tests/unit/mcap/mcap_test_util.h"

namespace rslam::mcap {
namespace {

using testing::DeclareChannels;
using testing::MakeMessages;
using testing::ScratchFolderForTest;
using testing::WriteAll;

bool HaveCommand(const std::string& name) {
  return std::system(("command -v " + name + " > /dev/null 2>&1").c_str()) == 0;
}

std::string RunCommand(const std::string& command, int& status) {
  std::string out;
  FILE* p = ::popen(command.c_str(), "r");
  if (!p) {
    status = -1;
    return out;
  }
  char buf[65536];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof(buf), p)) > 0) out.append(buf, n);
  status = ::pclose(p);
  return out;
}

// The npm packages, installed once per build tree. ctest runs these tests in parallel
// processes, so the install is serialised with a lock file.
std::string NodeModulesDir() {
  const std::string prefix = std::string(RSLAM_BINARY_DIR) + "/npm-mcap";
  const std::string modules = prefix + "/node_modules";
  std::filesystem::create_directories(prefix);
  const int lock = ::open((prefix + ".lock").c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644);
  if (lock >= 0) ::flock(lock, LOCK_EX);
  const std::vector<std::string> packages = {"@mcap/core", "@mcap/nodejs", "@mcap/support",
                                             "@foxglove/omgidl-parser",
                                             "@foxglove/omgidl-serialization"};
  std::string missing;
  for (const auto& p : packages) {
    if (!std::filesystem::exists(modules + "/" + p)) missing += " " + p;
  }
  if (!missing.empty()) {
    int status = 0;
    const std::string log = RunCommand(
        "npm install --no-audit --no-fund --silent --prefix '" + prefix + "'" + missing + " 2>&1",
        status);
    if (status != 0) ADD_FAILURE() << "npm install failed:\n" << log;
  }
  if (lock >= 0) ::close(lock);  // releases the lock
  return modules;
}

class IndependentReader : public ::testing::TestWithParam<std::string> {};

TEST_P(IndependentReader, OfficialMcapReadersAgreeWithWhatWasWritten) {
  if (!HaveCommand("node") || !HaveCommand("npm")) GTEST_SKIP() << "node/npm not installed";
  const std::string modules = NodeModulesDir();
  const auto path = ScratchFolderForTest() / "indep.mcap";
  const auto msgs = MakeMessages(400);
  McapWriterOptions o;
  o.compression = GetParam();
  o.chunk_size = 32 * 1024;
  o.profile = "rslam";
  std::vector<Channel> channels;
  std::vector<Schema> schemas;
  {
    McapWriter w;
    w.Open(path, o);
    DeclareChannels(w);
    WriteAll(w, msgs);
    channels = w.channels();
    schemas = w.schemas();
    w.Close();
  }
  int status = 0;
  const std::string script = std::string(RSLAM_SOURCE_DIR) + "/tests/unit/mcap/read_mcap.mjs";
  const std::string out = RunCommand("NODE_PATH='" + modules + "' node '" + script + "' '" +
                                  path.string() + "' 2>&1",
                              status);
  ASSERT_EQ(status, 0) << out;
  const auto j = nlohmann::json::parse(out);

  EXPECT_EQ(j["profile"], "rslam");
  EXPECT_EQ(j["library"], kRslamMcapLibrary);
  ASSERT_EQ(j["schemas"].size(), schemas.size());
  for (const auto& js : j["schemas"]) {
    const Schema& s = schemas.at(js["id"].get<int>() - 1);
    EXPECT_EQ(js["name"], s.name);
    EXPECT_EQ(js["encoding"], "omgidl");
    EXPECT_EQ(js["data"], s.data);
  }
  ASSERT_EQ(j["channels"].size(), channels.size());
  for (const auto& jc : j["channels"]) {
    const Channel& c = channels.at(jc["id"].get<int>() - 1);
    EXPECT_EQ(jc["topic"], c.topic);
    EXPECT_EQ(jc["schema_id"], c.schema_id);
    EXPECT_EQ(jc["message_encoding"], "cdr");
    EXPECT_EQ((jc["metadata"].get<std::map<std::string, std::string>>()), c.metadata);
  }
  ASSERT_FALSE(j["statistics"].is_null());
  EXPECT_EQ(j["statistics"]["message_count"], msgs.size());
  for (const auto& c : j["chunk_compressions"]) EXPECT_EQ(c, GetParam());

  // Every message, in log-time order, with the same bytes (CRC-32 + size of each payload).
  const auto expected = testing::InLogTimeOrder(msgs);
  const auto& jm = j["messages"];
  ASSERT_EQ(jm.size(), expected.size());
  std::map<int, uint64_t> per_channel;
  uint32_t crc_sum = 0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    SCOPED_TRACE("message " + std::to_string(i));
    const auto& m = expected[i];
    EXPECT_EQ(jm[i]["channel"], m.channel);
    EXPECT_EQ(jm[i]["sequence"], m.sequence);
    EXPECT_EQ(jm[i]["log_time"], std::to_string(m.log_time));
    EXPECT_EQ(jm[i]["publish_time"], std::to_string(m.publish_time));
    EXPECT_EQ(jm[i]["size"], m.data.size());
    const uint32_t crc = Crc32(m.data.data(), m.data.size());
    EXPECT_EQ(jm[i]["crc32"].get<uint32_t>(), crc);
    crc_sum += crc;
    ++per_channel[m.channel];
  }
  for (const auto& [ch, n] : per_channel) {
    EXPECT_EQ(j["statistics"]["channel_message_counts"][std::to_string(ch)], n);
  }
  EXPECT_EQ(j["stream_message_count"], msgs.size());
  EXPECT_EQ(j["stream_crc_sum"].get<uint32_t>(), crc_sum);
}

// Ping as hand-encoded XCDR1 little-endian: header 00 01 00 00, then (aligned relative to the
// end of the header) uint32 seq, string (u32 length with NUL, bytes, NUL), sequence<uint8>.
std::vector<std::byte> EncodePing(uint32_t seq, const std::string& text,
                                  const std::vector<uint8_t>& data) {
  std::vector<uint8_t> b = {0x00, 0x01, 0x00, 0x00};
  auto align4 = [&] {
    while ((b.size() - 4) % 4 != 0) b.push_back(0);
  };
  auto u32 = [&](uint32_t v) {
    align4();
    for (int i = 0; i < 4; ++i) b.push_back(static_cast<uint8_t>(v >> (8 * i)));
  };
  u32(seq);
  u32(static_cast<uint32_t>(text.size() + 1));
  b.insert(b.end(), text.begin(), text.end());
  b.push_back(0);
  u32(static_cast<uint32_t>(data.size()));
  b.insert(b.end(), data.begin(), data.end());
  std::vector<std::byte> out(b.size());
  std::memcpy(out.data(), b.data(), b.size());
  return out;
}

TEST(IndependentReader, DecodesHandEncodedCdrWithTheIdlSchema) {
  if (!HaveCommand("node") || !HaveCommand("npm")) GTEST_SKIP() << "node/npm not installed";
  const std::string modules = NodeModulesDir();
  const auto path = ScratchFolderForTest() / "ping.mcap";
  struct Ping {
    uint32_t seq;
    std::string text;
    std::vector<uint8_t> data;
  };
  std::vector<Ping> pings;
  for (uint32_t i = 0; i < 50; ++i) {
    std::vector<uint8_t> d(i * 5 % 23);
    for (std::size_t k = 0; k < d.size(); ++k) d[k] = static_cast<uint8_t>(i + 3 * k);
    pings.push_back({1000 + i, std::string(i % 7, static_cast<char>('a' + i % 26)), d});
  }
  {
    McapWriter w;
    w.Open(path);
    const uint16_t s = w.AddSchema("rslam::msg::Ping", "omgidl", testing::kPingIdl);
    const uint16_t ch = w.AddChannel(s, "/robot1/ping", "cdr", {{"robot", "robot1"}});
    for (uint32_t i = 0; i < pings.size(); ++i) {
      w.Write(ch, i, 1000 + i, 1000 + i, EncodePing(pings[i].seq, pings[i].text, pings[i].data));
    }
    w.Close();
  }
  int status = 0;
  const std::string script = std::string(RSLAM_SOURCE_DIR) + "/tests/unit/mcap/read_mcap.mjs";
  const std::string out = RunCommand("NODE_PATH='" + modules + "' node '" + script + "' '" +
                                         path.string() + "' --decode-cdr 2>&1",
                                     status);
  ASSERT_EQ(status, 0) << out;
  const auto j = nlohmann::json::parse(out);
  ASSERT_EQ(j["messages"].size(), pings.size());
  for (std::size_t i = 0; i < pings.size(); ++i) {
    SCOPED_TRACE("ping " + std::to_string(i));
    const auto& d = j["messages"][i]["decoded"];
    EXPECT_EQ(d["seq"], pings[i].seq);
    EXPECT_EQ(d["text"], pings[i].text);
    EXPECT_EQ(d["data"]["length"], pings[i].data.size());
    EXPECT_EQ(d["data"]["crc32"].get<uint32_t>(),
              Crc32(pings[i].data.data(), pings[i].data.size()));
  }
}

INSTANTIATE_TEST_SUITE_P(Compressions, IndependentReader, ::testing::Values("zstd", "lz4", ""),
                         [](const auto& info) {
                           return info.param.empty() ? std::string("none") : info.param;
                         });

}  // namespace
}  // namespace rslam::mcap
