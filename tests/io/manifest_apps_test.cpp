// panel_extract with a manifest, as a user runs it: rows match recordings by path relative to the
// manifest's folder, and a manifest that disagrees with what a recording holds says so in the row.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "io/metrics_csv.h"
#include "support/tools.h"
#include "test_dir.h"

namespace depthbias::io {
namespace {

namespace fs = std::filesystem;
using test_support::Bin;
using test_support::RunShell;

// Visual_Preset 3 (High Accuracy), Emitter_Enabled 1 (tests/data/bags/*.truth.json).
const std::string kBag = DEPTHBIAS_TEST_DATA "/bags/d455_depth_1mm.bag";

std::vector<records::PanelMetrics> Extract(const fs::path& manifest, const fs::path& bag,
                                           const fs::path& dir, int* code) {
  const auto out = dir / "m.csv";
  const auto r = RunShell(Bin("panel_extract") + " --quiet --manifest " + manifest.string() +
                              " --out " + out.string() + " " + bag.string(),
                          dir);
  *code = r.code;
  EXPECT_TRUE(fs::exists(out)) << r.err;
  return fs::exists(out) ? ReadMetricsCsv(out.string()) : std::vector<records::PanelMetrics>{};
}

TEST(ManifestApps, ARecordingOfTheSameNameElsewhereDoesNotTakeTheRowsTruth) {
  const fs::path d = testing::FreshDir("io");
  fs::create_directories(d / "unit");
  fs::create_directories(d / "elsewhere");
  fs::copy_file(kBag, d / "unit" / "rec.bag");
  fs::copy_file(kBag, d / "elsewhere" / "rec.bag");
  std::ofstream(d / "unit" / "manifest.csv") << "bag,distance_m,angle_deg,light\n"
                                                "rec.bag,4,0,daylight\n";
  int code = 0;
  auto rows = Extract(d / "unit" / "manifest.csv", d / "elsewhere" / "rec.bag", d, &code);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(code, 1);
  EXPECT_EQ(rows[0].status, "error");
  EXPECT_NE(rows[0].message.find("not listed in"), std::string::npos) << rows[0].message;
  EXPECT_TRUE(std::isnan(rows[0].distance_m));
  rows = Extract(d / "unit" / "manifest.csv", d / "unit" / "rec.bag", d, &code);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_DOUBLE_EQ(rows[0].distance_m, 4.0);
  EXPECT_EQ(rows[0].message.find("not listed"), std::string::npos) << rows[0].message;
}

TEST(ManifestApps, AManifestThatDisagreesWithTheRecordingSaysSoInTheRow) {
  const fs::path d = testing::FreshDir("io");
  fs::copy_file(kBag, d / "rec.bag");
  std::ofstream(d / "manifest.csv") << "bag,distance_m,angle_deg,light,preset,emitter\n"
                                       "rec.bag,4,0,daylight,HD,off\n";
  int code = 0;
  auto rows = Extract(d / "manifest.csv", d / "rec.bag", d, &code);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].preset, "HD");  // the manifest's word is used ...
  EXPECT_EQ(rows[0].emitter, "off");
  const std::string& msg = rows[0].message;  // ... and the disagreement is said
  EXPECT_NE(msg.find("preset 'HD' differs from the recording's Visual_Preset 'HA'"),
            std::string::npos) << msg;
  EXPECT_NE(msg.find("emitter 'off' differs from the recording's Emitter_Enabled 'on'"),
            std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos);
  // Agreeing columns say nothing.
  std::ofstream(d / "manifest.csv") << "bag,distance_m,angle_deg,light,preset,emitter\n"
                                       "rec.bag,4,0,daylight,HA,on\n";
  rows = Extract(d / "manifest.csv", d / "rec.bag", d, &code);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].message.find("differs"), std::string::npos) << rows[0].message;
}

}  // namespace
}  // namespace depthbias::io
