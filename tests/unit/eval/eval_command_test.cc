#include "tools/eval/eval_command.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/child_process.h"
#include "tests/unit/eval/eval_test_files.h"

namespace rslam::eval {
namespace {

using rslam::testing::ScratchFolderForTest;
using testing::RunRslam;
using testing::WriteText;

TEST(EvalCommand, TrajectoryPrintsAteAsJson) {
  const auto dir = ScratchFolderForTest();
  WriteText(dir / "truth.csv", "stamp_ns,x,y\n0,0,0\n1000,2,0\n2000,2,2\n3000,0,2\n");
  WriteText(dir / "estimate.csv", "stamp_ns,x,y\n0,0,0\n1000,1,0\n2000,1,1\n3000,0,1\n");
  const auto json = nlohmann::json::parse(RunRslam({"eval", "trajectory", "--estimate", (dir / "estimate.csv").string(),
                                               "--ground-truth", (dir / "truth.csv").string(), "--json"}));
  EXPECT_NEAR(json["ate_m"].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(json["scale"].get<double>(), 2.0, 1e-9);
  EXPECT_EQ(json["pairs"].get<int>(), 4);
  const auto rigid = nlohmann::json::parse(RunRslam({"eval", "trajectory", "--estimate", (dir / "estimate.csv").string(),
                                                "--ground-truth", (dir / "truth.csv").string(), "--json", "--no-scale"}));
  EXPECT_DOUBLE_EQ(rigid["scale"].get<double>(), 1.0);
  EXPECT_GT(rigid["ate_m"].get<double>(), 0.5);
  std::filesystem::remove_all(dir);
}

TEST(EvalCommand, BadCsvFailsWithTheLineInTheMessage) {
  const auto dir = ScratchFolderForTest();
  WriteText(dir / "truth.csv", "stamp_ns,x,y\n0,0,0\n1000,oops,0\n");
  try {
    RunRslam({"eval", "trajectory", "--estimate", (dir / "truth.csv").string(), "--ground-truth",
         (dir / "truth.csv").string()});
    FAIL() << "no error";
  } catch (const CLI::RuntimeError& e) {
    EXPECT_EQ(e.get_exit_code(), 1);
    EXPECT_NE(std::string(e.what()).find("truth.csv:3: x 'oops'"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(EvalCommand, VprScoresFrameAlignedFolders) {
  const auto dir = ScratchFolderForTest();
  for (const char* season : {"summer", "winter"}) std::filesystem::create_directories(dir / season);
  cv::RNG random(7);
  for (int k = 0; k < 12; ++k) {
    cv::Mat place(32, 64, CV_8UC1);
    random.fill(place, cv::RNG::UNIFORM, 0, 256);
    cv::Mat winter;
    place.convertTo(winter, CV_8U, 0.6, 60);  // same place, other light
    const std::string name = "images-" + std::to_string(100 + k) + ".png";
    cv::imwrite((dir / "summer" / name).string(), place);
    cv::imwrite((dir / "winter" / name).string(), winter);
  }
  const auto json = nlohmann::json::parse(RunRslam({"eval", "vpr", "--reference", (dir / "summer").string(), "--query",
                                               (dir / "winter").string(), "--matcher", "baseline", "--json"}));
  EXPECT_DOUBLE_EQ(json["recall_at_1"].get<double>(), 1.0);
  EXPECT_EQ(json["queries"].get<int>(), 12);
  EXPECT_EQ(json["mode"].get<std::string>(), "single");
  const auto sequence = nlohmann::json::parse(RunRslam({"eval", "vpr", "--reference", (dir / "summer").string(), "--query",
                                                   (dir / "winter").string(), "--matcher", "baseline",
                                                   "--sequence", "3", "--json"}));
  EXPECT_EQ(sequence["mode"].get<std::string>(), "sequence");
  EXPECT_EQ(sequence["contrast_window"].get<int>(), 10);
  std::filesystem::remove_all(dir);
}

TEST(EvalCommand, VprBadInputIsAClearError) {
  const auto dir = ScratchFolderForTest();
  std::filesystem::create_directories(dir / "empty");
  try {
    RunRslam({"eval", "vpr", "--reference", (dir / "empty").string(), "--query", (dir / "empty").string()});
    FAIL() << "no error";
  } catch (const CLI::RuntimeError& e) {
    EXPECT_NE(std::string(e.what()).find("holds no images"), std::string::npos) << e.what();
  }
  EXPECT_THROW(RunRslam({"eval", "vpr", "--reference", "a", "--query", "b", "--sequence", "0"}), CLI::ValidationError);
  EXPECT_THROW(RunRslam({"eval", "vpr", "--query", "b"}), CLI::RequiredError);
  EXPECT_THROW(RunRslam({"eval", "vpr", "--reference", "a", "--query", "b", "--preset", "no_such_preset_anywhere"}),
               CLI::RuntimeError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rslam::eval
