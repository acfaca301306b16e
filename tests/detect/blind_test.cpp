// A blind camera is not a clear scene. Recordings written with io's BagWriter whose depth is all
// zero, all at full scale (65535), or 1 x 1 px: obstacle_detector marks every frame blind (never
// zone clear), writes its output and exits 1, counting the blind frames in its summary; a
// recording that is blind in one frame of three exits 1 with that frame alone blind.
// panel_extract gives such recordings no row of metrics (status not ok, exit 1).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "io/bag.h"
#include "io/metrics_csv.h"
#include "support/tools.h"

namespace depthbias {
namespace {

namespace fs = std::filesystem;

using test_support::Bin;
using test_support::ReadFile;
using test_support::RunShell;

// A wall 5 m ahead fills the frame ("wall"), or nothing ("zero"), or every pixel at full scale
// ("full"); a 64 × 48 px camera unless `side_px` says otherwise.
void WriteBag(const fs::path& path, const std::vector<std::string>& frames, int side_px = 0) {
  io::BagWriterConfig c;
  c.intrinsics.width = side_px ? side_px : 64;
  c.intrinsics.height = side_px ? side_px : 48;
  c.intrinsics.fx = c.intrinsics.fy = side_px ? side_px : 40.0;
  c.intrinsics.ppx = c.intrinsics.width / 2.0;
  c.intrinsics.ppy = c.intrinsics.height / 2.0;
  c.intrinsics.coeffs = {0, 0, 0, 0, 0};
  c.options = {{"Visual_Preset", 4}, {"Emitter_Enabled", 1}};
  io::BagWriter w(path.string(), c);
  for (size_t i = 0; i < frames.size(); ++i) {
    records::DepthFrame f;
    f.width = c.intrinsics.width, f.height = c.intrinsics.height;
    f.frame_number = i, f.timestamp_ms = 1000.0 + 33.0 * i;
    const std::uint16_t value = frames[i] == "wall" ? 5000 : frames[i] == "full" ? 65535 : 0;
    f.counts.assign(static_cast<size_t>(f.width) * f.height, value);
    w.Write(f);
  }
  w.Close();
}

std::vector<YAML::Node> Lines(const fs::path& path) {
  std::vector<YAML::Node> out;
  std::istringstream in(ReadFile(path));
  for (std::string line; std::getline(in, line);) out.push_back(YAML::Load(line));
  return out;
}

class BlindCamera : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* app : {"obstacle_detector", "panel_extract", "fit_bias"})
      ASSERT_TRUE(fs::exists(Bin(app))) << app << " is not built";
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(DEPTHBIAS_BINARY_DIR) / "test_tmp" / (std::string("blind_") + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    weights_ = (dir_ / "w.yaml").string();
    const std::string fit = Bin("fit_bias") + " --in " DEPTHBIAS_SOURCE_DIR
                            "/config/data/paper_d455_outdoor.csv --cv none --out " + weights_ +
                            " > /dev/null";
    ASSERT_EQ(std::system(fit.c_str()), 0);
  }
  test_support::ToolRun Detect(const fs::path& bag, const fs::path& out) {
    return RunShell(Bin("obstacle_detector") + " --weights " + weights_ + " --out " +
                        out.string() + " " + bag.string(),
                    dir_);
  }
  fs::path dir_;
  std::string weights_;
};

TEST_F(BlindCamera, EveryFrameOfABlindRecordingIsBlindNeverClearAndTheRunExitsOne) {
  WriteBag(dir_ / "zero.bag", {"zero", "zero", "zero"});
  WriteBag(dir_ / "full.bag", {"full", "full", "full"});
  WriteBag(dir_ / "one_px.bag", {"wall", "wall", "wall"}, 1);
  for (const char* name : {"zero", "full", "one_px"}) {
    const fs::path out = dir_ / (std::string(name) + ".jsonl");
    const auto r = Detect(dir_ / (std::string(name) + ".bag"), out);
    EXPECT_EQ(r.code, 1) << name << ": " << r.err << r.out;
    EXPECT_NE(r.out.find("3 frames: 0 ok, 3 blind"), std::string::npos) << name << ": " << r.out;
    const auto lines = Lines(out);
    ASSERT_EQ(lines.size(), 3u) << name;
    for (const YAML::Node& l : lines) {
      EXPECT_EQ(l["status"].as<std::string>(), "blind") << name;
      EXPECT_EQ(l["valid_pct"].as<double>(), 0.0) << name;
      EXPECT_EQ(l["zone"].as<std::string>(), "stop") << name;
      for (const YAML::Node& o : l["obstacles"])
        EXPECT_NE(o["zone"].as<std::string>(), "clear") << name;
    }
  }
}

TEST_F(BlindCamera, OneBlindFrameAmongSeenOnesIsCountedAndOnlyItIsBlind) {
  WriteBag(dir_ / "mixed.bag", {"wall", "zero", "wall"});
  const auto r = Detect(dir_ / "mixed.bag", dir_ / "mixed.jsonl");
  EXPECT_EQ(r.code, 1) << r.err << r.out;
  EXPECT_NE(r.out.find("3 frames: 2 ok, 1 blind"), std::string::npos) << r.out;
  const auto lines = Lines(dir_ / "mixed.jsonl");
  ASSERT_EQ(lines.size(), 3u);
  for (int i : {0, 2}) {
    EXPECT_EQ(lines[i]["status"].as<std::string>(), "ok");
    EXPECT_EQ(lines[i]["valid_pct"].as<double>(), 100.0);
  }
  EXPECT_EQ(lines[1]["status"].as<std::string>(), "blind");
  // A recording that is seen throughout exits 0.
  WriteBag(dir_ / "walls.bag", {"wall", "wall"});
  const auto ok = Detect(dir_ / "walls.bag", dir_ / "walls.jsonl");
  EXPECT_EQ(ok.code, 0) << ok.err << ok.out;
  EXPECT_NE(ok.out.find("2 frames: 2 ok;"), std::string::npos) << ok.out;
}

TEST_F(BlindCamera, PanelExtractGivesABlindRecordingNoMetrics) {
  fs::create_directories(dir_ / "bags");
  WriteBag(dir_ / "bags" / "zero.bag", {"zero", "zero", "zero"});
  WriteBag(dir_ / "bags" / "full.bag", {"full", "full", "full"});
  WriteBag(dir_ / "bags" / "one_px.bag", {"wall", "wall", "wall"}, 1);
  const auto r = RunShell(Bin("panel_extract") + " --quiet --out " + (dir_ / "m.csv").string() +
                              " " + (dir_ / "bags").string(),
                          dir_);
  EXPECT_EQ(r.code, 1) << r.err << r.out;
  const auto rows = io::ReadMetricsCsv((dir_ / "m.csv").string());
  ASSERT_EQ(rows.size(), 3u);
  for (const auto& m : rows) EXPECT_NE(m.status, "ok") << m.bag << ": " << m.message;
}

}  // namespace
}  // namespace depthbias
