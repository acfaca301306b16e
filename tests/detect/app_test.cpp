// obstacle_detector's command line: usage, a run on a recording librealsense wrote, and every
// bad input refused in one line that names it, with no output left behind.
#include <gtest/gtest.h>


#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "support/tools.h"

namespace depthbias {
namespace {

namespace fs = std::filesystem;

using test_support::Bin;
using test_support::ReadFile;
using test_support::RunShell;

using Result = test_support::ToolRun;

Result Exec(const std::string& args, const fs::path& dir) {
  return RunShell(Bin("obstacle_detector") + " " + args, dir);
}

const std::string kBag = DEPTHBIAS_TEST_DATA "/bags/d455_depth_1mm.bag";  // HA, emitter on

class ObstacleDetectorCli : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(Bin("obstacle_detector"))) << "obstacle_detector is not built";
    // One folder per test: ctest runs the tests of this file in parallel.
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(DEPTHBIAS_BINARY_DIR) / "test_tmp" / (std::string("obstacle_detector_") +
                                                          info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    weights_ = (dir_ / "w.yaml").string();
    const std::string fit = Bin("fit_bias") + " --in " DEPTHBIAS_SOURCE_DIR
                            "/config/data/paper_d455_outdoor.csv --cv none --out " + weights_ +
                            " > /dev/null";
    ASSERT_EQ(std::system(fit.c_str()), 0);
    out_ = (dir_ / "d.jsonl").string();
  }
  void ExpectCleanFailure(const std::string& args, const std::string& needle) {
    const Result r = Exec(args, dir_);
    EXPECT_NE(r.code, 0) << args;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << args << " -> " << r.err;
    EXPECT_FALSE(fs::exists(out_)) << args;
  }
  fs::path dir_;
  std::string weights_, out_;
};

TEST_F(ObstacleDetectorCli, HelpAndARunOnALibrealsenseRecording) {
  const Result help = Exec("--help", dir_);
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.out.find("usage: obstacle_detector --weights"), std::string::npos);
  const Result r = Exec("--weights " + weights_ + " --out " + out_ + " " + kBag, dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("daylight/HA/emitter on"), std::string::npos) << r.out;  // from options
  const std::string lines = ReadFile(out_);
  EXPECT_EQ(std::count(lines.begin(), lines.end(), '\n'), 4);  // one line per frame
  EXPECT_EQ(lines.rfind("{\"frame\": 0, \"timestamp_s\": 1000.000000, \"obstacles\": [", 0), 0u)
      << lines;
}

TEST_F(ObstacleDetectorCli, BadInputsFailInOneLineWithoutOutput) {
  const std::string w = "--weights " + weights_ + " --out " + out_ + " ";
  ExpectCleanFailure(w + "--kk 2 " + kBag, "unknown argument '--kk'");
  ExpectCleanFailure("--weights " + weights_ + " " + kBag, "usage");
  ExpectCleanFailure(w + (dir_ / "missing.bag").string(), "missing.bag");
  ExpectCleanFailure(w + kBag + " " + kBag, "one recording only");
  ExpectCleanFailure(w + "--k -1 " + kBag, "--k");
  ExpectCleanFailure(w + "--light dusk " + kBag, "dusk");
  ExpectCleanFailure("--weights " + weights_ + " --out " + weights_ + " " + kBag,
                     "is also an input");
  std::ofstream(dir_ / "bad.yaml") << "cluster: {tolerance_m: 0.3}\n";
  ExpectCleanFailure(w + "--config " + (dir_ / "bad.yaml").string() + " " + kBag,
                     "bad.yaml: unknown key 'cluster.tolerance_m'");
  // Weights without a range-dependent margin (schema 1) are refused.
  std::string text = ReadFile(weights_);
  text.replace(text.find("depthbias.weights/2"), 19, "depthbias.weights/1");
  for (const char* key : {"near_guard:", "noise_pooled:"}) {
    const size_t at = text.find(key);
    text.erase(at, text.find('\n', at) + 1 - at);
  }
  while (text.find("    margin: ") != std::string::npos) {
    const size_t at = text.find("    margin: ");
    text.erase(at, text.find('\n', at) + 1 - at);
  }
  std::ofstream(dir_ / "old.yaml") << text;
  ExpectCleanFailure("--weights " + (dir_ / "old.yaml").string() + " --out " + out_ + " " + kBag,
                     "refit with fit_bias");
  EXPECT_EQ(ReadFile(weights_).find("depthbias.weights/2") != std::string::npos, true);  // untouched
}

}  // namespace
}  // namespace depthbias
