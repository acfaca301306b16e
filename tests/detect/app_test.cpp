// obstacle_detector's command line: usage, a run on a recording librealsense wrote, and every
// bad input refused in one line that names it, with no output left behind.
#include <gtest/gtest.h>


#include <algorithm>
#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

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
  // Exit 2 (nothing written), one line on stderr holding `needle`, no output.
  void ExpectCleanFailure(const std::string& args, const std::string& needle) {
    const Result r = Exec(args, dir_);
    EXPECT_EQ(r.code, 2) << args;
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
  EXPECT_EQ(lines.rfind("{\"frame\": 0, \"timestamp_s\": 1000, \"status\": \"ok\", ", 0), 0u)
      << lines;
}

TEST_F(ObstacleDetectorCli, BadInputsFailInOneLineWithoutOutput) {
  const std::string w = "--weights " + weights_ + " --out " + out_ + " ";
  ExpectCleanFailure(w + "--kk 2 " + kBag, "unknown argument '--kk'");
  ExpectCleanFailure("--weights " + weights_ + " " + kBag, "usage");
  ExpectCleanFailure(w + (dir_ / "missing.bag").string(), "missing.bag");
  ExpectCleanFailure(w + kBag + " " + kBag, "one recording only");
  ExpectCleanFailure(w + "--k -1 " + kBag, "--k '-1' is outside (0, 10]");
  ExpectCleanFailure(w + "--k 0 " + kBag, "--k '0' is outside (0, 10]");
  ExpectCleanFailure(w + "--k 10.5 " + kBag, "--k '10.5' is outside (0, 10]");
  ExpectCleanFailure(w + "--k 1e308 " + kBag, "--k '1e308' is outside (0, 10]");
  ExpectCleanFailure(w + "--k 1e999 " + kBag, "--k '1e999' is outside (0, 10]");
  ExpectCleanFailure(w + "--k nan " + kBag, "--k 'nan' is not a number");
  ExpectCleanFailure(w + "--k 2x " + kBag, "--k '2x' is not a number");
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

// A k too small for a double's normal range is still a number in (0, 10]: the run goes on.
TEST_F(ObstacleDetectorCli, ATinyKIsANumber) {
  const Result r = Exec("--weights " + weights_ + " --k 1e-320 --out " + out_ + " " + kBag, dir_);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("not a finite number"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("k 9.99989e-321"), std::string::npos) << r.out;  // the nearest double
}

// What the bias model refuses in a weights file names that file: a disparity form without its
// focal length, a group with a weight too few for its form.
TEST_F(ObstacleDetectorCli, WeightsTheModelRefusesAreNamed) {
  const std::string text = ReadFile(weights_);
  std::string no_focal = text;
  ASSERT_NE(no_focal.find("\nfocal_px: 640\n"), std::string::npos) << text;
  no_focal.replace(no_focal.find("\nfocal_px: 640\n"), 15, "\nfocal_px: 0\n");
  std::string fewer = text;
  const size_t k35 = fewer.find("      k_35deg:");
  ASSERT_NE(k35, std::string::npos) << text;
  fewer.erase(k35, fewer.find('\n', k35) + 1 - k35);
  const size_t cov = fewer.find("    covariance:\n");
  fewer.replace(cov, fewer.find("  - light:", cov) - cov, "    covariance: []\n");
  for (const auto& [name, contents, says] : std::vector<std::array<std::string, 3>>{
           {"no_focal.yaml", no_focal, "needs focal_px > 0"},
           {"fewer.yaml", fewer, "4 weights"}}) {
    std::ofstream(dir_ / name) << contents;
    const Result r =
        Exec("--weights " + (dir_ / name).string() + " --out " + out_ + " " + kBag, dir_);
    EXPECT_EQ(r.code, 2) << name << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(r.err.rfind("obstacle_detector: " + (dir_ / name).string() + ": ", 0), 0u)
        << r.err;
    EXPECT_NE(r.err.find(says), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out_));
  }
}

}  // namespace
}  // namespace depthbias
