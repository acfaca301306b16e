#include "io/manifest.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "test_dir.h"

namespace depthbias::io {
namespace {

std::string ErrorOf(const std::string& text) {
  try {
    ParseManifest(text, "man.csv");
  } catch (const IoError& e) {
    return e.what();
  }
  return "";
}

TEST(Manifest, RequiredOptionalAndExtraColumns) {
  const Manifest m = ParseManifest(
      "bag,distance_m,angle_deg,light,preset,emitter,true_depth_m,true_hole_rate_pct\n"
      "rec/a.bag,4,0,daylight,HA,on,4.02,3.5\n"
      "b.bag,8,35,sunset,,,,\n",
      "man.csv");
  ASSERT_EQ(m.rows().size(), 2u);
  EXPECT_EQ(m.extra_columns(), (std::vector<std::string>{"true_depth_m", "true_hole_rate_pct"}));
  // Matched by path, relative to the manifest's folder (here the working folder).
  EXPECT_EQ(m.Find("/data/other/a.bag"), nullptr);
  const ManifestRow* a = m.Find("rec/a.bag");
  ASSERT_NE(a, nullptr);
  EXPECT_DOUBLE_EQ(a->distance_m, 4.0);
  EXPECT_EQ(a->preset.value_or(""), "HA");
  EXPECT_EQ(a->emitter.value_or(""), "on");
  EXPECT_EQ(a->extras.at("true_depth_m"), "4.02");
  const ManifestRow* b = m.Find("b.bag");
  ASSERT_NE(b, nullptr);
  EXPECT_FALSE(b->preset.has_value());
  EXPECT_FALSE(b->emitter.has_value());
  EXPECT_EQ(b->line, 3);
  EXPECT_EQ(m.Find("c.bag"), nullptr);
}

// A row names a recording by its path relative to the manifest's own folder: a file of the same
// name elsewhere (/etc/<name>.bag, another unit's folder) never takes its truth.
TEST(Manifest, RowsMatchByPathRelativeToTheManifestNotByName) {
  namespace fs = std::filesystem;
  const fs::path d = testing::FreshDir("io");
  fs::create_directories(d / "unit" / "sub");
  fs::create_directories(d / "other");
  const std::string file = (d / "unit" / "manifest.csv").string();
  std::ofstream(file) << "bag,distance_m,angle_deg,light\na.bag,4,0,daylight\n"
                      << "sub/b.bag,8,10,sunset\n" << (d / "other" / "c.bag").string()
                      << ",12,20,daylight\n";
  const Manifest m = ReadManifest(file);
  ASSERT_NE(m.Find((d / "unit" / "a.bag").string()), nullptr);
  EXPECT_NE(m.Find((d / "unit" / "sub" / ".." / "a.bag").string()), nullptr);  // normalized
  EXPECT_EQ(m.Find("/etc/a.bag"), nullptr);
  EXPECT_EQ(m.Find((d / "other" / "a.bag").string()), nullptr);
  EXPECT_EQ(m.Find("a.bag"), nullptr);  // the working folder is not the manifest's
  ASSERT_NE(m.Find((d / "unit" / "sub" / "b.bag").string()), nullptr);
  EXPECT_DOUBLE_EQ(m.Find((d / "unit" / "sub" / "b.bag").string())->distance_m, 8.0);
  EXPECT_EQ(m.Find((d / "unit" / "b.bag").string()), nullptr);
  ASSERT_NE(m.Find((d / "other" / "c.bag").string()), nullptr);  // an absolute row
  // A link to a listed recording is that recording.
  std::ofstream(d / "unit" / "a.bag") << "x";
  fs::create_symlink(d / "unit" / "a.bag", d / "other" / "link.bag");
  EXPECT_NE(m.Find((d / "other" / "link.bag").string()), nullptr);
  // Two rows for one recording, written differently, are refused.
  EXPECT_THROW(ParseManifest("bag,distance_m,angle_deg,light\na.bag,4,0,x\n./a.bag,8,0,x\n",
                             file),
               IoError);
  // Two recordings of the same name in different folders are two rows.
  EXPECT_NO_THROW(ParseManifest("bag,distance_m,angle_deg,light\na.bag,4,0,x\nsub/a.bag,8,0,x\n",
                                file));
  fs::remove_all(d);
}

TEST(Manifest, WithoutOptionalColumns) {
  const Manifest m = ParseManifest("bag,distance_m,angle_deg,light\nx.bag,12,20,daylight\n", "m");
  ASSERT_EQ(m.rows().size(), 1u);
  EXPECT_TRUE(m.extra_columns().empty());
}

TEST(Manifest, ErrorsNameFileAndLine) {
  const std::string dup = ErrorOf(
      "bag,distance_m,angle_deg,light\na.bag,4,0,daylight\nx/../a.bag,8,0,daylight\n");
  EXPECT_NE(dup.find("man.csv:3"), std::string::npos) << dup;
  EXPECT_NE(dup.find("line 2"), std::string::npos) << dup;
  const std::string bad = ErrorOf("bag,distance_m,angle_deg,light\na.bag,4m,0,daylight\n");
  EXPECT_NE(bad.find("man.csv:2"), std::string::npos) << bad;
  EXPECT_NE(bad.find("distance_m"), std::string::npos) << bad;
  EXPECT_NE(ErrorOf("bag,distance_m,angle_deg,light\na.bag,-4,0,daylight\n")
                .find("-4 is outside (0, 1000] m"),
            std::string::npos);
  EXPECT_NE(ErrorOf("bag,distance_m,light\na.bag,4,daylight\n").find("angle_deg"),
            std::string::npos);
  EXPECT_NE(ErrorOf("bag,distance_m,angle_deg,light,emitter\na.bag,4,0,d,maybe\n")
                .find("emitter"),
            std::string::npos);
}

TEST(Manifest, WriteThenReadRoundTrips) {
  ManifestRow r;
  r.bag = "a.bag";
  r.distance_m = 16;
  r.angle_deg = -10;
  r.light = "sunset";
  r.preset = "HD";
  r.extras["true_depth_m"] = "15.9";
  const auto dir = testing::FreshDir("io");
  const std::string path = (dir / "m.csv").string();
  WriteManifest(path, {r}, {"true_depth_m"});
  const Manifest m = ReadManifest(path);
  ASSERT_EQ(m.rows().size(), 1u);
  EXPECT_DOUBLE_EQ(m.rows()[0].angle_deg, -10.0);
  EXPECT_EQ(m.rows()[0].preset.value_or(""), "HD");
  EXPECT_FALSE(m.rows()[0].emitter.has_value());
  EXPECT_EQ(m.rows()[0].extras.at("true_depth_m"), "15.9");
}

}  // namespace
}  // namespace depthbias::io
