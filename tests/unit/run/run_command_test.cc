// `rslam run` end to end: output files, determinism, errors and exit codes (through the
// test-only CLI, as a user runs it), and the real data when present.
#include "tools/run/run_command.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "synthetic_loop.h"
#include "tests/support/child_process.h"

namespace rslam::run {
namespace {

namespace fs = std::filesystem;
using testing::SyntheticLoop;

using ::rslam::testing::ScratchFolder;

std::string ReadFile(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> Lines(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// Two laps and a bit of the synthetic loop as PNG files, plus its config file.
struct LoopRecording {
  explicit LoopRecording(const fs::path& root, int frames = 80) : images(root / "frames"), config(root / "loop.yaml") {
    fs::create_directories(images);
    const SyntheticLoop loop(36);
    for (int i = 0; i < frames; ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "frame_%04d.bmp", i);
      cv::imwrite((images / name).string(), loop.Frame(i));
    }
    std::ofstream(config) << SyntheticLoop::ConfigYaml();
  }
  fs::path images;
  fs::path config;
};

RunOptions LoopOptions(const LoopRecording& recording, const fs::path& out) {
  RunOptions options;
  options.images = recording.images.string();
  options.config_file = recording.config.string();
  options.out_dir = out.string();
  options.progress = RunOptions::Progress::kQuiet;
  return options;
}

struct CliResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

CliResult RunCli(const std::string& arguments) {
  const std::string command = std::string(RSLAM_BINARY_DIR) + "/bin/rslam_run_cli run " + arguments + " 2>&1";
  CliResult result;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buffer;
  while (const size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe)) result.output.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

const char* SharedData() { return std::getenv("RSLAM_SHARED_DATA"); }

TEST(RunCommand, WritesOutputsWhoseCountsAgree) {
  ScratchFolder dir;
  const LoopRecording recording(dir.path());
  const fs::path out = dir.path() / "out";
  std::stringstream stdout_text, stderr_text;
  ASSERT_EQ(RunRatSlamCommand(LoopOptions(recording, out), stdout_text, stderr_text), 0) << stderr_text.str();

  const nlohmann::json summary = nlohmann::json::parse(ReadFile(out / "summary.json"));
  EXPECT_EQ(summary["frames"], 80);
  EXPECT_EQ(summary["relaxed"], true);
  EXPECT_GE(summary["loop_closures"].get<int>(), 1);
  EXPECT_GT(summary["fps_core"].get<double>(), 0.0);
  for (const char* stage : {"odometry", "templates", "pose_cells", "experience_map"}) {
    EXPECT_GT(summary["ms_per_frame"][stage].get<double>(), 0.0) << stage;
  }
  EXPECT_NE(summary["source"].get<std::string>().find("frames"), std::string::npos);

  const std::vector<std::string> experiences = Lines(out / "experiences.csv");
  ASSERT_FALSE(experiences.empty());
  EXPECT_EQ(experiences[0], "id,x,y,theta,template_id");
  EXPECT_EQ(experiences.size() - 1, summary["experiences"].get<size_t>());

  const std::vector<std::string> templates = Lines(out / "templates.csv");
  ASSERT_EQ(templates.size(), 81u);
  EXPECT_EQ(templates[0], "frame,stamp_ns,template_id,is_new,template_count");
  const std::string last = templates.back();
  EXPECT_EQ(last.substr(last.rfind(',') + 1), std::to_string(summary["templates"].get<int>()));
  EXPECT_LT(summary["templates"].get<int>(), 40) << "the second lap is recognised";

  for (const char* image : {"experience_map.png", "templates.png"}) {
    const cv::Mat png = cv::imread((out / image).string());
    ASSERT_FALSE(png.empty()) << image;
    EXPECT_GE(png.cols, 400) << image;
  }
}

TEST(RunCommand, TwoRunsWriteIdenticalExperiences) {
  ScratchFolder dir;
  const LoopRecording recording(dir.path());
  std::stringstream ignored;
  ASSERT_EQ(RunRatSlamCommand(LoopOptions(recording, dir.path() / "a"), ignored, ignored), 0) << ignored.str();
  ASSERT_EQ(RunRatSlamCommand(LoopOptions(recording, dir.path() / "b"), ignored, ignored), 0) << ignored.str();
  const std::string a = ReadFile(dir.path() / "a" / "experiences.csv");
  EXPECT_GT(a.size(), 100u);
  EXPECT_EQ(a, ReadFile(dir.path() / "b" / "experiences.csv"));
  EXPECT_EQ(ReadFile(dir.path() / "a" / "templates.csv"), ReadFile(dir.path() / "b" / "templates.csv"));
}

TEST(RunCommand, MaxFramesStopsEarly) {
  ScratchFolder dir;
  const LoopRecording recording(dir.path(), 20);
  RunOptions options = LoopOptions(recording, dir.path() / "out");
  options.max_frames = 7;
  std::stringstream ignored;
  ASSERT_EQ(RunRatSlamCommand(options, ignored, ignored), 0) << ignored.str();
  EXPECT_EQ(nlohmann::json::parse(ReadFile(dir.path() / "out" / "summary.json"))["frames"], 7);
}

TEST(RunCommand, ReadsAVideoWithItsOwnStamps) {
  ScratchFolder dir;
  const fs::path video = dir.path() / "loop.avi";
  {
    cv::VideoWriter writer(video.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10, cv::Size(640, 480));
    if (!writer.isOpened()) GTEST_SKIP() << "no video writer in this OpenCV build";
    const SyntheticLoop loop(36);
    for (int i = 0; i < 20; ++i) writer.write(loop.Frame(i));
  }
  std::ofstream(dir.path() / "loop.yaml") << SyntheticLoop::ConfigYaml();
  RunOptions options;
  options.video = video.string();
  options.config_file = (dir.path() / "loop.yaml").string();
  options.out_dir = (dir.path() / "out").string();
  options.progress = RunOptions::Progress::kQuiet;
  std::stringstream out, err;
  ASSERT_EQ(RunRatSlamCommand(options, out, err), 0) << err.str();
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(dir.path() / "out" / "summary.json"));
  EXPECT_EQ(summary["frames"], 20);
  EXPECT_GE(summary["templates"].get<int>(), 15) << "JPEG noise does not merge different places";
  const auto templates = Lines(dir.path() / "out" / "templates.csv");
  ASSERT_EQ(templates.size(), 21u);
  EXPECT_EQ(templates[3].substr(0, templates[3].find(',', 2)), "2,200000000") << "the file's 10 Hz stamps";

  std::ofstream(dir.path() / "garbage.avi") << "not a video at all";
  options.video = (dir.path() / "garbage.avi").string();
  std::stringstream err2;
  EXPECT_EQ(RunRatSlamCommand(options, out, err2), 1);
  EXPECT_NE(err2.str().find("garbage.avi"), std::string::npos) << err2.str();
}

TEST(RunCommandCli, RunsAndReportsTheResult) {
  ScratchFolder dir;
  const LoopRecording recording(dir.path(), 12);
  const CliResult r = RunCli("--images " + recording.images.string() + " --config " + recording.config.string() +
                             " --set templates.match_threshold=0.09 --fps 5 --out " + (dir.path() / "out").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("12 frames"), std::string::npos) << r.output;
  const auto templates = Lines(dir.path() / "out" / "templates.csv");
  ASSERT_GE(templates.size(), 3u);
  EXPECT_EQ(templates[2].substr(0, templates[2].find(',', 2)), "1,200000000") << "stamps at --fps 5";
}

TEST(RunCommandCli, MissingOutIsAnError) {
  const CliResult r = RunCli("--images /nonexistent");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--out"), std::string::npos) << r.output;
}

TEST(RunCommandCli, UnknownPresetExitsTwoNamingIt) {
  ScratchFolder dir;
  const LoopRecording recording(dir.path(), 2);
  const CliResult r = RunCli("--images " + recording.images.string() + " --preset no_such_place --out " +
                             (dir.path() / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("no_such_place"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir.path() / "out" / "summary.json"));
}

TEST(RunCommandCli, UnknownConfigKeyExitsTwoNamingIt) {
  ScratchFolder dir;
  const LoopRecording recording(dir.path(), 2);
  const CliResult r = RunCli("--images " + recording.images.string() +
                             " --preset stlucia --set templates.bogus_key=3 --out " + (dir.path() / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("templates.bogus_key"), std::string::npos) << r.output;

  std::ofstream(dir.path() / "bad.yaml") << "odometry:\n  camera_hz: 10\nlocal_view:\n  x: 1\n";
  const CliResult section = RunCli("--images " + recording.images.string() + " --config " +
                                   (dir.path() / "bad.yaml").string() + " --out " + (dir.path() / "out").string());
  EXPECT_EQ(section.exit_code, 2) << section.output;
  EXPECT_NE(section.output.find("local_view"), std::string::npos) << section.output;

  const CliResult value = RunCli("--images " + recording.images.string() + " --set pose_cells.pc_dim_xy=-4 --out " +
                                 (dir.path() / "out").string());
  EXPECT_EQ(value.exit_code, 2) << value.output;
  EXPECT_NE(value.output.find("pose_cells.pc_dim_xy"), std::string::npos) << value.output;
}

TEST(RunCommandCli, BadInputExitsOneWithTheReason) {
  ScratchFolder dir;
  const std::string out = " --out " + (dir.path() / "out").string();
  const CliResult missing = RunCli("--images " + (dir.path() / "nowhere").string() + out);
  EXPECT_EQ(missing.exit_code, 1) << missing.output;
  EXPECT_NE(missing.output.find("nowhere"), std::string::npos) << missing.output;

  fs::create_directories(dir.path() / "empty");
  const CliResult empty = RunCli("--images " + (dir.path() / "empty").string() + out);
  EXPECT_EQ(empty.exit_code, 1) << empty.output;
  EXPECT_NE(empty.output.find("no images"), std::string::npos) << empty.output;

  fs::create_directories(dir.path() / "broken");
  cv::imwrite((dir.path() / "broken" / "a.png").string(), SyntheticLoop(36).Frame(0));
  std::ofstream(dir.path() / "broken" / "b.png") << "this is not a png";
  const CliResult broken = RunCli("--images " + (dir.path() / "broken").string() + out);
  EXPECT_EQ(broken.exit_code, 1) << broken.output;
  EXPECT_NE(broken.output.find("b.png"), std::string::npos) << broken.output;

  const CliResult video = RunCli("--video " + (dir.path() / "missing.mp4").string() + out);
  EXPECT_EQ(video.exit_code, 1) << video.output;
  EXPECT_NE(video.output.find("missing.mp4"), std::string::npos) << video.output;

  const CliResult neither = RunCli(out);
  EXPECT_EQ(neither.exit_code, 2) << neither.output;
}

TEST(RunCommandRealData, IratFramesWithTheIratPreset) {
  if (!SharedData() || !fs::is_directory(fs::path(SharedData()) / "irat")) GTEST_SKIP() << "no shared data";
  ScratchFolder dir;
  RunOptions options;
  options.images = (fs::path(SharedData()) / "irat").string();
  options.preset = "irat";
  options.out_dir = (dir.path() / "out").string();
  options.progress = RunOptions::Progress::kQuiet;
  std::stringstream out, err;
  ASSERT_EQ(RunRatSlamCommand(options, out, err), 0) << err.str();
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(dir.path() / "out" / "summary.json"));
  EXPECT_EQ(summary["frames"], 10);
  EXPECT_GE(summary["templates"].get<int>(), 2) << "two runs in different places";
  EXPECT_LE(summary["templates"].get<int>(), 10);
  EXPECT_GE(summary["experiences"].get<int>(), 1);
  EXPECT_EQ(summary["preset"], "irat");
  EXPECT_EQ(Lines(dir.path() / "out" / "experiences.csv").size() - 1, summary["experiences"].get<size_t>());
}

TEST(RunCommandRealData, NordlandSummerWithTheNordlandPreset) {
  if (!SharedData() || !fs::is_directory(fs::path(SharedData()) / "nordland" / "summer"))
    GTEST_SKIP() << "no shared data";
  ScratchFolder dir;
  RunOptions options;
  options.images = (fs::path(SharedData()) / "nordland" / "summer").string();
  options.preset = "nordland";
  options.max_frames = 200;
  options.out_dir = (dir.path() / "out").string();
  options.progress = RunOptions::Progress::kQuiet;
  std::stringstream out, err;
  ASSERT_EQ(RunRatSlamCommand(options, out, err), 0) << err.str();
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(dir.path() / "out" / "summary.json"));
  EXPECT_EQ(summary["frames"], 200);
  // A train on a line: mostly new views, but not one template per frame of the same stretch.
  EXPECT_GE(summary["templates"].get<int>(), 50);
  EXPECT_LE(summary["templates"].get<int>(), 200);
  EXPECT_GE(summary["experiences"].get<int>(), 50);
  EXPECT_EQ(summary["relaxed"], true);
  const auto experiences = Lines(dir.path() / "out" / "experiences.csv");
  EXPECT_EQ(experiences.size() - 1, summary["experiences"].get<size_t>());
  for (size_t i = 1; i < experiences.size(); ++i) {
    EXPECT_EQ(experiences[i].find("nan"), std::string::npos) << experiences[i];
    EXPECT_EQ(experiences[i].find("inf"), std::string::npos) << experiences[i];
  }
}

}  // namespace
}  // namespace rslam::run
