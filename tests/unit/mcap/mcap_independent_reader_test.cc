// Files written by McapWriter read back identically with the official Foxglove readers
// (@mcap/core indexed + streaming readers, @mcap/support decompression) via read_mcap.mjs.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "common/mcap/mcap_crc32.h"
#include "tests/unit/mcap/mcap_test_util.h"

namespace rslam::mcap {
namespace {

using testing::DeclareChannels;
using testing::MakeMessages;
using testing::ScratchDir;
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

// The npm packages, installed once per build tree.
std::string NodeModulesDir() {
  const std::string prefix = std::string(RSLAM_BINARY_DIR) + "/npm-mcap";
  const std::string modules = prefix + "/node_modules";
  if (!std::filesystem::exists(modules + "/@mcap/core") ||
      !std::filesystem::exists(modules + "/@mcap/nodejs") ||
      !std::filesystem::exists(modules + "/@mcap/support")) {
    int status = 0;
    const std::string log = RunCommand("npm install --no-audit --no-fund --silent --prefix '" + prefix +
                                    "' @mcap/core @mcap/nodejs @mcap/support 2>&1",
                                status);
    if (status != 0) ADD_FAILURE() << "npm install failed:\n" << log;
  }
  return modules;
}

class IndependentReader : public ::testing::TestWithParam<std::string> {};

TEST_P(IndependentReader, OfficialMcapReadersAgreeWithWhatWasWritten) {
  if (!HaveCommand("node") || !HaveCommand("npm")) GTEST_SKIP() << "node/npm not installed";
  const std::string modules = NodeModulesDir();
  const auto path = ScratchDir() / "indep.mcap";
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

INSTANTIATE_TEST_SUITE_P(Compressions, IndependentReader, ::testing::Values("zstd", "lz4", ""),
                         [](const auto& info) {
                           return info.param.empty() ? std::string("none") : info.param;
                         });

}  // namespace
}  // namespace rslam::mcap
