// McapWriter → OpenRecording: a written MCAP file reads back frame for frame, with its
// intrinsics and the wrapper's parameters, in both chunk forms; and the writer refuses what a
// 16UC1 image cannot hold.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "io/io_error.h"
#include "io/mcap_writer.h"
#include "io/recording.h"
#include "io/rosbag2_metadata.h"

namespace depthbias::io {
namespace {

std::vector<records::DepthFrame> Frames(int n, int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<records::DepthFrame> frames(n);
  for (int i = 0; i < n; ++i) {
    records::DepthFrame& f = frames[i];
    f.width = w;
    f.height = h;
    f.timestamp_ms = 1000.0 + 33.3 * i;
    f.counts.resize(static_cast<std::size_t>(w) * h);
    for (auto& c : f.counts) c = rng() % 4 == 0 ? 0 : static_cast<std::uint16_t>(rng() % 20000);
  }
  return frames;
}

std::string Path(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::path(DEPTHBIAS_BINARY_DIR) / "test_tmp" / "mcap_writer";
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

TEST(McapWriter, RoundTripsFramesIntrinsicsAndParameters) {
  for (const bool zstd : {false, true}) {
    SCOPED_TRACE(zstd ? "zstd" : "uncompressed");
    McapWriterConfig config;
    config.zstd = zstd;
    config.bag.intrinsics.width = 64;
    config.bag.intrinsics.height = 48;
    config.bag.intrinsics.fx = 40.5;
    config.bag.intrinsics.fy = 41.0;
    config.bag.intrinsics.ppx = 31.25;
    config.bag.intrinsics.ppy = 23.5;
    config.bag.intrinsics.coeffs = {0.01, -0.02, 0.001, 0.002, 0.003};
    config.bag.options = {{"Visual_Preset", 4}, {"Emitter_Enabled", 0}};
    const std::string path = Path(zstd ? "zstd.mcap" : "plain.mcap");
    const std::vector<records::DepthFrame> frames = Frames(7, 64, 48, zstd ? 1 : 2);
    {
      McapWriter writer(path, config);
      for (const auto& f : frames) writer.Write(f);
      writer.Close();
    }
    EXPECT_FALSE(std::filesystem::exists(path + ".part"));
    const auto source = OpenRecording(path);
    const BagInfo& info = source->info();
    EXPECT_EQ(info.depth_frames, frames.size());
    EXPECT_TRUE(info.indexed);
    EXPECT_EQ(info.compressed, zstd);
    ASSERT_TRUE(info.has_depth_intrinsics);
    EXPECT_DOUBLE_EQ(info.depth_intrinsics.fx, 40.5);
    EXPECT_DOUBLE_EQ(info.depth_intrinsics.fy, 41.0);
    EXPECT_DOUBLE_EQ(info.depth_intrinsics.ppx, 31.25);
    EXPECT_DOUBLE_EQ(info.depth_intrinsics.coeffs[4], 0.003);
    EXPECT_EQ(source->settings_source(), "parameter messages");
    EXPECT_EQ(info.options.at("Visual_Preset"), 4.0);
    EXPECT_EQ(info.options.at("Emitter_Enabled"), 0.0);
    records::DepthFrame f;
    for (const auto& truth : frames) {
      ASSERT_TRUE(source->Next(&f));
      EXPECT_TRUE(f.counts == truth.counts);
      EXPECT_NEAR(f.timestamp_ms, truth.timestamp_ms + 1000.0, 1e-3);  // stamps from 1 s
    }
    EXPECT_FALSE(source->Next(&f));
  }
}

TEST(McapWriter, RefusesUnitsOtherThanMillimetresAndWrongSizes) {
  McapWriterConfig config;
  config.bag.depth_units_m = 0.0001;
  EXPECT_THROW(McapWriter(Path("units.mcap"), config), BagError);
  config.bag.depth_units_m = 0.001;
  McapWriter writer(Path("size.mcap"), config);
  EXPECT_THROW(writer.Write(Frames(1, 8, 8, 3)[0]), BagError);
}

TEST(Rosbag2Metadata, RefusesWhatIsNotRosbag2sAndAliasBombs) {
  EXPECT_THROW(ParseRosbag2Metadata("a: 1\n", "m.yaml"), IoError);
  EXPECT_THROW(ParseRosbag2Metadata("rosbag2_bagfile_information:\n  version: 5\n", "m.yaml"),
               IoError);
  EXPECT_THROW(ParseRosbag2Metadata("rosbag2_bagfile_information:\n  relative_file_paths: "
                                    "[../../etc/passwd]\n", "m.yaml"),
               IoError);
  std::string bomb = "a0: &a0 [x, x, x, x, x, x, x, x, x]\n";
  for (int i = 1; i < 9; ++i)
    bomb += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [" +
            std::string("*a") + std::to_string(i - 1) + ", *a" + std::to_string(i - 1) +
            ", *a" + std::to_string(i - 1) + ", *a" + std::to_string(i - 1) + ", *a" +
            std::to_string(i - 1) + ", *a" + std::to_string(i - 1) + ", *a" +
            std::to_string(i - 1) + ", *a" + std::to_string(i - 1) + ", *a" +
            std::to_string(i - 1) + "]\n";
  EXPECT_THROW(ParseRosbag2Metadata(bomb, "bomb.yaml"), IoError);
  const Rosbag2Metadata m = ParseRosbag2Metadata(
      "rosbag2_bagfile_information:\n  version: 9\n  storage_identifier: mcap\n"
      "  relative_file_paths: [r_0.mcap]\n  duration: {nanoseconds: 5}\n"
      "  topics_with_message_count:\n    - topic_metadata: {name: /a, type: t/msg/A, "
      "serialization_format: cdr}\n      message_count: 3\n", "m.yaml");
  EXPECT_EQ(m.storage_identifier, "mcap");
  ASSERT_EQ(m.topics.size(), 1u);
  EXPECT_EQ(m.topics[0].messages, 3u);
  EXPECT_EQ(m.duration_ns, 5);
}

}  // namespace
}  // namespace depthbias::io
