// The rosbag2 reader against recordings written by other people's writers (the `rosbags`
// package: MCAP and SQLite3 folders; the `mcap` + `mcap-ros2-support` packages: zstd and lz4
// chunks), all holding the frames of one ROS 1 bag written by librealsense's recorder
// (scripts/make_ros2_fixtures.py, run by the fixture test before these), and damaged copies.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "io/csv.h"
#include "io/recording.h"
#include "io/rosbag2_source.h"
#include "support/tools.h"

namespace depthbias::io {
namespace {

const std::string kDir = DEPTHBIAS_ROS2_FIXTURES;
const std::vector<std::string> kRos2 = {"rosbags_mcap", "rosbags_sqlite", "mcap_zstd.mcap",
                                        "mcap_lz4.mcap"};

std::vector<records::DepthFrame> ReadAll(RecordingSource* source) {
  std::vector<records::DepthFrame> frames;
  records::DepthFrame f;
  while (source->Next(&f)) frames.push_back(f);
  return frames;
}

TEST(Rosbag2, FormatIsChosenByWhatThePathIs) {
  EXPECT_EQ(FormatOf(kDir + "/ros1.bag"), RecordingFormat::kRos1Bag);
  EXPECT_EQ(FormatOf(kDir + "/rosbags_mcap"), RecordingFormat::kRosbag2Folder);
  EXPECT_EQ(FormatOf(kDir + "/rosbags_sqlite"), RecordingFormat::kRosbag2Folder);
  EXPECT_EQ(FormatOf(kDir + "/mcap_zstd.mcap"), RecordingFormat::kMcap);
  EXPECT_EQ(FormatOf(kDir + "/rosbags_sqlite/rosbags_sqlite.db3"), RecordingFormat::kSqlite);
}

TEST(Rosbag2, EveryFormGivesTheRos1BagsFramesAndIntrinsics) {
  const auto ros1 = OpenRecording(kDir + "/ros1.bag");
  const std::vector<records::DepthFrame> truth = ReadAll(ros1.get());
  ASSERT_GT(truth.size(), 5u);
  for (const std::string& name : kRos2) {
    SCOPED_TRACE(name);
    const auto source = OpenRecording(kDir + "/" + name);
    const BagInfo& info = source->info();
    EXPECT_EQ(info.depth.topic, "/camera/camera/depth/image_rect_raw");
    EXPECT_EQ(info.depth_frames, truth.size());
    ASSERT_TRUE(info.has_depth_intrinsics);
    const camera::Intrinsics& a = info.depth_intrinsics;
    const camera::Intrinsics& b = ros1->info().depth_intrinsics;
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_FLOAT_EQ(a.fx, b.fx);
    EXPECT_FLOAT_EQ(a.ppx, b.ppx);
    EXPECT_FLOAT_EQ(a.ppy, b.ppy);
    EXPECT_EQ(a.model, b.model);
    for (int pass = 0; pass < 2; ++pass) {  // and again after Rewind
      const std::vector<records::DepthFrame> got = ReadAll(source.get());
      ASSERT_EQ(got.size(), truth.size());
      for (std::size_t i = 0; i < got.size(); ++i) {
        EXPECT_EQ(got[i].width, truth[i].width);
        EXPECT_DOUBLE_EQ(got[i].depth_units_m, truth[i].depth_units_m);
        EXPECT_TRUE(got[i].counts == truth[i].counts) << "frame " << i;
      }
      ASSERT_TRUE(source->Rewind());
    }
  }
}

TEST(Rosbag2, CompressionAndSettingsAreReportedWithTheirSource) {
  const auto zstd = OpenRecording(kDir + "/mcap_zstd.mcap");
  const auto lz4 = OpenRecording(kDir + "/mcap_lz4.mcap");
  EXPECT_NE(zstd->SummaryText().find("Compression:       zstd"), std::string::npos)
      << zstd->SummaryText();
  EXPECT_NE(lz4->SummaryText().find("Compression:       lz4"), std::string::npos);
  EXPECT_TRUE(zstd->info().indexed);
  EXPECT_EQ(zstd->settings_source(), "");  // recorded without parameters
  const auto params = OpenRecording(kDir + "/rosbags_mcap");
  EXPECT_EQ(params->settings_source(), "parameter messages");
  EXPECT_EQ(params->info().options.at("Visual_Preset"), 3.0);
  EXPECT_EQ(params->info().options.at("Emitter_Enabled"), 1.0);
  const auto sqlite = OpenRecording(kDir + "/rosbags_sqlite");
  EXPECT_EQ(sqlite->settings_source(), "");
  EXPECT_NE(sqlite->SummaryText().find("Missing:"), std::string::npos);
  EXPECT_NE(sqlite->SummaryText().find("Storage id:        sqlite3"), std::string::npos);
}

TEST(Rosbag2, TopicGivenByName) {
  EXPECT_NO_THROW(OpenRecording(kDir + "/mcap_zstd.mcap",
                                {"/camera/camera/depth/image_rect_raw", false}));
  try {
    OpenRecording(kDir + "/mcap_zstd.mcap", {"/camera/camera/depth/camera_info", false});
    FAIL() << "a CameraInfo topic taken as depth";
  } catch (const BagError& e) {
    EXPECT_EQ(e.kind(), BagError::Kind::kNoDepthStream);
  }
  EXPECT_THROW(OpenRecording(kDir + "/mcap_zstd.mcap", {"/nothing", false}), BagError);
}

// A recording cut short (writer crashed: no summary, no footer) gives its whole chunks.
TEST(Rosbag2, CutShortMcapGivesItsFramesUpToTheCut) {
  const auto ros1 = OpenRecording(kDir + "/ros1.bag");
  const std::vector<records::DepthFrame> truth = ReadAll(ros1.get());
  const auto cut = OpenRecording(kDir + "/bad/cut.mcap");
  EXPECT_FALSE(cut->info().indexed);
  EXPECT_NE(cut->damage(), "");
  const std::vector<records::DepthFrame> got = ReadAll(cut.get());
  ASSERT_GT(got.size(), 0u);
  ASSERT_LT(got.size(), truth.size());
  EXPECT_EQ(cut->info().depth_frames, got.size());
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_TRUE(got[i].counts == truth[i].counts);
}

TEST(Rosbag2, DamagedAndHostileFilesAreRefusedInOneLineNamingTheFile) {
  for (const std::string name : {"flipped.mcap", "huge_record.mcap", "huge_chunk.mcap",
                                 "huge_image.mcap", "other_size.mcap", "notmcap.mcap", "cut.db3",
                                 "garbage.db3"}) {
    SCOPED_TRACE(name);
    const std::string path = kDir + "/bad/" + name;
    try {
      const auto source = OpenRecording(path);
      ReadAll(source.get());
      FAIL() << "read without error";
    } catch (const BagError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
}

// The tool itself: panel_extract on the ROS 1 bag and on every ROS 2 form, with the manifest,
// gives one identical metrics row (all columns but the recording's name).
TEST(Rosbag2, PanelExtractGivesTheSameRowForEveryForm) {
  const std::filesystem::path out =
      std::filesystem::path(DEPTHBIAS_BINARY_DIR) / "test_tmp" / "rosbag2_rows";
  std::filesystem::create_directories(out);
  std::string cmd = test_support::Bin("panel_extract") + " --quiet --manifest " + kDir +
                    "/manifest.csv --out " + (out / "metrics.csv").string() + " --panels-out " +
                    (out / "panels.json").string() + " " + kDir + "/ros1.bag";
  for (const std::string& name : kRos2) cmd += " " + kDir + "/" + name;
  const test_support::ToolRun run = test_support::RunShell(cmd, out);
  ASSERT_EQ(run.code, 0) << run.err;
  const CsvTable table = ReadCsv((out / "metrics.csv").string());
  ASSERT_EQ(table.rows.size(), 1 + kRos2.size());
  const int status = table.RequireColumn("status");
  EXPECT_EQ(table.rows[0][status], "ok");
  for (std::size_t r = 1; r < table.rows.size(); ++r)
    for (std::size_t c = 1; c < table.header.size(); ++c)
      EXPECT_EQ(table.rows[r][c], table.rows[0][c]) << kRos2[r - 1] << " " << table.header[c];
  EXPECT_NE(test_support::ReadFile(out / "panels.json").find("\"settings_from\": \"manifest\""),
            std::string::npos);
}

// A recording cut short gives its frames up to the cut, and its metrics row says so: a row from
// a crashed recording never reads as a whole one.
TEST(Rosbag2, PanelExtractRowOfACutShortRecordingSaysWhereItStops) {
  const std::filesystem::path out =
      std::filesystem::path(DEPTHBIAS_BINARY_DIR) / "test_tmp" / "rosbag2_cut_row";
  std::filesystem::create_directories(out);
  const std::string cut = kDir + "/bad/cut.mcap";
  const test_support::ToolRun run = test_support::RunShell(
      test_support::Bin("panel_extract") + " --quiet --out " + (out / "metrics.csv").string() +
          " " + cut + " " + kDir + "/ros1.bag",
      out);
  ASSERT_LE(run.code, 1) << run.err;
  const CsvTable table = ReadCsv((out / "metrics.csv").string());
  ASSERT_EQ(table.rows.size(), 2u);
  const int message = table.RequireColumn("message");
  EXPECT_NE(table.rows[0][message].find(cut + ": read up to where it stops being readable ("),
            std::string::npos)
      << table.rows[0][message];
  EXPECT_EQ(table.rows[1][message].find("stops being readable"), std::string::npos);
}

// obstacle_detector on ROS 2 recordings: the preset and emitter from the recorded parameters,
// else from --preset and --emitter; without either, or against the recording, refused in one
// line naming the recording.
TEST(Rosbag2, ObstacleDetectorTakesPresetAndEmitterFromTheRecordingElseTheCommandLine) {
  const std::filesystem::path out =
      std::filesystem::path(DEPTHBIAS_BINARY_DIR) / "test_tmp" / "rosbag2_detector";
  std::filesystem::remove_all(out);
  std::filesystem::create_directories(out);
  const std::string weights = (out / "w.yaml").string();
  ASSERT_EQ(test_support::RunShell(test_support::Bin("fit_bias") + " --in " DEPTHBIAS_SOURCE_DIR
                                   "/config/data/paper_d455_outdoor.csv --cv none --out " +
                                   weights, out).code, 0);
  const std::string detector = test_support::Bin("obstacle_detector") + " --weights " + weights +
                               " --out " + (out / "d.jsonl").string() + " ";
  const std::string bare = kDir + "/mcap_zstd.mcap";           // no parameter messages
  const std::string with = kDir + "/rosbags_mcap";             // HA, emitter on recorded
  test_support::ToolRun run = test_support::RunShell(detector + bare, out);
  EXPECT_EQ(run.code, 2);
  EXPECT_EQ(run.err, "obstacle_detector: " + bare + ": no recorded preset (Visual_Preset) "
                     "(rosbag2 MCAP file without it): give --preset\n");
  EXPECT_FALSE(std::filesystem::exists(out / "d.jsonl"));
  run = test_support::RunShell(detector + "--preset HD --emitter off " + bare, out);
  EXPECT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.out.find("daylight/HD/emitter off from --preset and --emitter"),
            std::string::npos) << run.out;
  run = test_support::RunShell(detector + with, out);
  EXPECT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.out.find("daylight/HA/emitter on from parameter messages"), std::string::npos)
      << run.out;
  run = test_support::RunShell(detector + "--preset HD " + with, out);
  EXPECT_EQ(run.code, 2);
  EXPECT_EQ(run.err, "obstacle_detector: " + with + ": --preset HD differs from the recording's "
                     "preset (Visual_Preset) HA\n");
  run = test_support::RunShell(detector + "--emitter maybe " + bare, out);
  EXPECT_EQ(run.code, 2);
  EXPECT_NE(run.err.find("--emitter 'maybe' is neither on nor off"), std::string::npos);
}

TEST(Rosbag2, BagInfoReadsLikeRos2BagInfo) {
  const std::filesystem::path out =
      std::filesystem::path(DEPTHBIAS_BINARY_DIR) / "test_tmp" / "rosbag2_info";
  std::filesystem::create_directories(out);
  const test_support::ToolRun run =
      test_support::RunShell(test_support::Bin("bag_info") + " " + kDir + "/rosbags_mcap", out);
  ASSERT_EQ(run.code, 0) << run.err;
  for (const char* key : {"Files:", "Bag size:", "Storage id:        mcap", "Duration:",
                          "Messages:", "Topic information: Topic: ",
                          "Type: sensor_msgs/msg/Image", "Intrinsics:",
                          "Preset/emitter:    Visual_Preset 3, Emitter_Enabled 1 (from parameter"})
    EXPECT_NE(run.out.find(key), std::string::npos) << key << "\n" << run.out;
  const test_support::ToolRun bad = test_support::RunShell(
      test_support::Bin("bag_info") + " " + kDir + "/bad/huge_record.mcap", out);
  EXPECT_EQ(bad.code, 1);
  EXPECT_EQ(bad.err.rfind("bag_info: " + kDir + "/bad/huge_record.mcap: ", 0), 0u) << bad.err;
}

}  // namespace
}  // namespace depthbias::io
