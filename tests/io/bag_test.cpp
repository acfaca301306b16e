// BagReader and BagWriter against bags written by librealsense's own recorder (tests/data/bags,
// made by scripts/make_fixture_bags.py with the truth of every pixel, intrinsic, unit and option),
// round trips through BagWriter, and damaged or wrong input of every kind.

#include <unistd.h>

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "camera/intrinsics.h"
#include "camera/presets.h"
#include "io/bag.h"

namespace depthbias::io {
namespace {

namespace fs = std::filesystem;
using Kind = BagError::Kind;

std::string FixturePath(const std::string& name) {
  return std::string(DEPTHBIAS_TEST_DATA) + "/bags/" + name;
}

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// A fresh folder per test.
class TempDir {
 public:
  TempDir() {
    const auto* t = ::testing::UnitTest::GetInstance()->current_test_info();
    // The process id keeps two build trees' runs of the same test apart (both use /tmp).
    std::string name = "depthbias_io_" + std::string(t->test_suite_name()) + "_" + t->name() +
                       "_" + std::to_string(::getpid());
    std::replace(name.begin(), name.end(), '/', '_');
    path_ = fs::path(::testing::TempDir()) / name;
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string File(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
};

// Opens the bag and reads every frame; returns the error it throws (or fails the test).
BagError::Kind ExpectBagError(const std::string& path, ReadOptions options = {}) {
  try {
    BagReader reader(path, options);
    records::DepthFrame frame;
    while (reader.Next(&frame)) {
    }
  } catch (const BagError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_EQ(e.file(), path);
    return e.kind();
  }
  ADD_FAILURE() << path << " read without error";
  return Kind::kWrite;
}

std::size_t Replace(std::string* s, const std::string& from, const std::string& to) {
  std::size_t n = 0;
  for (std::size_t at = s->find(from); at != std::string::npos;
       at = s->find(from, at + to.size())) {
    s->replace(at, from.size(), to);
    ++n;
  }
  return n;
}

// ---------------------------------------------------------------- librealsense-written bags

struct Truth {
  YAML::Node node;
  explicit Truth(const std::string& bag) {
    node = YAML::LoadFile(FixturePath(bag.substr(0, bag.size() - 4) + ".truth.json"));
  }
};

class RecordedBag : public ::testing::TestWithParam<std::string> {};

TEST_P(RecordedBag, ReturnsExactlyWhatTheRecorderWasGiven) {
  const std::string path = FixturePath(GetParam());
  const Truth truth(GetParam());
  const YAML::Node& t = truth.node;
  BagReader reader(path);
  const BagInfo& info = reader.info();

  EXPECT_EQ(info.compressed, t["compressed"].as<bool>());
  EXPECT_TRUE(info.indexed);
  ASSERT_TRUE(info.has_depth_intrinsics);
  const camera::Intrinsics& in = info.depth_intrinsics;
  const YAML::Node& ti = t["intrinsics"];
  EXPECT_EQ(in.width, ti["width"].as<int>());
  EXPECT_EQ(in.height, ti["height"].as<int>());
  EXPECT_EQ(in.fx, ti["fx"].as<double>());
  EXPECT_EQ(in.fy, ti["fy"].as<double>());
  EXPECT_EQ(in.ppx, ti["ppx"].as<double>());
  EXPECT_EQ(in.ppy, ti["ppy"].as<double>());
  std::string model = ti["model"].as<std::string>();  // e.g. distortion.brown_conrady
  model = model.substr(model.find('.') + 1);
  camera::Distortion want_model;
  ASSERT_TRUE(camera::ParseDistortion(model, &want_model)) << model;
  EXPECT_EQ(in.model, want_model);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(in.coeffs[i], ti["coeffs"][i].as<double>()) << i;

  const double units = t["depth_units"].as<double>();
  EXPECT_EQ(info.depth_units_m, units);
  for (const auto& kv : t["options"]) {
    const std::string name = kv.first.as<std::string>();
    ASSERT_TRUE(info.options.count(name)) << name;
    EXPECT_EQ(info.options.at(name), kv.second.as<double>()) << name;
  }
  for (const auto& kv : t["device"])
    EXPECT_EQ(info.device.at(kv.first.as<std::string>()), kv.second.as<std::string>());

  std::set<std::string> streams, want_streams;
  for (const StreamInfo& s : info.streams)
    streams.insert(s.stream_type + "_" + std::to_string(s.stream_index));
  for (const auto& s : t["streams"]) want_streams.insert(s.as<std::string>());
  EXPECT_EQ(streams, want_streams);
  EXPECT_EQ(info.depth.encoding, "mono16");
  EXPECT_EQ(info.depth.sensor_index, 0);

  const YAML::Node& frames = t["frames"];
  ASSERT_EQ(info.depth_frames, frames.size());
  EXPECT_NEAR(info.first_timestamp_ms, frames[0]["timestamp_ms"].as<double>(), 1e-6);
  EXPECT_NEAR(info.last_timestamp_ms, frames[frames.size() - 1]["timestamp_ms"].as<double>(),
              1e-6);
  records::DepthFrame frame;
  std::size_t i = 0;
  for (; reader.Next(&frame); ++i) {
    ASSERT_LT(i, frames.size());
    const YAML::Node& tf = frames[i];
    EXPECT_EQ(frame.frame_number, tf["frame_number"].as<std::uint64_t>());
    EXPECT_NEAR(frame.timestamp_ms, tf["timestamp_ms"].as<double>(), 1e-6);
    EXPECT_EQ(frame.depth_units_m, units);
    ASSERT_EQ(frame.width, in.width);
    ASSERT_EQ(frame.height, in.height);
    const auto pixels = tf["pixels"].as<std::vector<int>>();
    ASSERT_EQ(frame.counts.size(), pixels.size());
    std::size_t differ = 0;
    for (std::size_t k = 0; k < pixels.size(); ++k) differ += frame.counts[k] != pixels[k];
    EXPECT_EQ(differ, 0u) << "frame " << i;
  }
  EXPECT_EQ(i, frames.size());
  EXPECT_TRUE(reader.damage().empty());
  EXPECT_FALSE(reader.Next(&frame));  // stays at the end
}

INSTANTIATE_TEST_SUITE_P(Fixtures, RecordedBag,
                         ::testing::Values("d455_depth_1mm.bag", "d455_depth_100um_lz4.bag",
                                           "d455_depth_color_imu_lz4.bag",
                                           "d455_depth_color_imu.bag"),
                         [](const auto& p) {
                           std::string n = p.param.substr(0, p.param.size() - 4);
                           for (char& c : n)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return n;
                         });

TEST(RecordedBagInfo, ListsEveryStreamWithItsFormat) {
  BagReader reader(FixturePath("d455_depth_color_imu.bag"));
  std::map<std::string, StreamInfo> by_name;
  for (const StreamInfo& s : reader.info().streams)
    by_name[s.stream_type + "_" + std::to_string(s.stream_index)] = s;
  ASSERT_EQ(by_name.size(), 4u);
  EXPECT_EQ(by_name["Color_0"].sensor_index, 1);
  EXPECT_EQ(by_name["Color_0"].encoding, "rgb8");
  EXPECT_EQ(by_name["Color_0"].width, 96);
  EXPECT_EQ(by_name["Infrared_1"].sensor_index, 0);
  EXPECT_EQ(by_name["Accel_0"].sensor_index, 2);
  EXPECT_EQ(by_name["Accel_0"].topic, "/device_0/sensor_2/Accel_0/imu/data");
  for (const auto& [name, s] : by_name) EXPECT_EQ(s.messages, 3u) << name;
  EXPECT_EQ(reader.info().sensor.at("Name"), "Stereo Module");
}

// rosbag_storage's own reader (rosbag::View) sees the same depth frames as BagReader.
TEST_P(RecordedBag, AgreesWithRosbagStorage) {
  const std::string path = FixturePath(GetParam());
  BagReader reader(path);
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  rosbag::View view(bag, rosbag::TopicQuery(reader.info().depth.topic));
  records::DepthFrame frame;
  std::size_t n = 0;
  for (const rosbag::MessageInstance& m : view) {
    const sensor_msgs::Image::ConstPtr image = m.instantiate<sensor_msgs::Image>();
    ASSERT_TRUE(image);
    ASSERT_TRUE(reader.Next(&frame));
    ++n;
    EXPECT_EQ(frame.frame_number, image->header.seq);
    EXPECT_NEAR(frame.timestamp_ms, image->header.stamp.toSec() * 1e3, 1e-3);
    ASSERT_EQ(static_cast<std::uint32_t>(frame.width), image->width);
    ASSERT_EQ(static_cast<std::uint32_t>(frame.height), image->height);
    std::size_t differ = 0;
    for (int v = 0; v < frame.height; ++v)
      for (int u = 0; u < frame.width; ++u) {
        const std::uint8_t* p = image->data.data() + v * image->step + 2 * u;
        differ += frame.at(u, v) != static_cast<std::uint16_t>(p[0] | (p[1] << 8));
      }
    EXPECT_EQ(differ, 0u);
  }
  EXPECT_GT(n, 0u);
  EXPECT_EQ(n, reader.info().depth_frames);
  EXPECT_FALSE(reader.Next(&frame));
}

// The same recording rewritten by rosbag_storage with one message per chunk (so most chunks hold
// no depth frame and are skipped by the index), uncompressed and LZ4.
TEST(RecordedBagRechunked, OneMessagePerChunkGivesTheSameFrames) {
  TempDir dir;
  const std::string source = FixturePath("d455_depth_color_imu.bag");
  const Truth truth("d455_depth_color_imu.bag");
  for (bool lz4 : {false, true}) {
    const std::string path = dir.File(lz4 ? "rechunked_lz4.bag" : "rechunked.bag");
    {
      rosbag::Bag in(source, rosbag::bagmode::Read);
      rosbag::Bag out(path, rosbag::bagmode::Write);
      out.setChunkThreshold(1);
      if (lz4) out.setCompression(rosbag::compression::LZ4);
      rosbag::View view(in);
      for (const rosbag::MessageInstance& m : view)
        out.write(m.getTopic(), m.getTime(), m, m.getConnectionHeader());
    }
    BagReader reader(path);
    EXPECT_EQ(reader.info().streams.size(), 4u);
    EXPECT_EQ(reader.info().depth_frames, truth.node["frames"].size());
    EXPECT_EQ(reader.info().options.at("Visual_Preset"), 4.0);
    records::DepthFrame f;
    std::size_t i = 0;
    for (; reader.Next(&f); ++i) {
      ASSERT_LT(i, truth.node["frames"].size());
      const auto pixels = truth.node["frames"][i]["pixels"].as<std::vector<int>>();
      EXPECT_TRUE(std::equal(pixels.begin(), pixels.end(), f.counts.begin())) << i;
    }
    EXPECT_EQ(i, truth.node["frames"].size()) << "lz4 " << lz4;
  }
}

// rosbag::Bag loads a plugin through class_loader, which is not thread-safe on its own; a batch
// reads several recordings at once, so readers on several threads must all succeed.
TEST(RecordedBagThreads, ReadersOnSeveralThreadsAtOnce) {
  const std::vector<std::string> names = {"d455_depth_1mm.bag", "d455_depth_100um_lz4.bag",
                                          "d455_depth_color_imu.bag",
                                          "d455_depth_color_imu_lz4.bag"};
  std::vector<std::string> errors(names.size());
  std::vector<int> frames(names.size(), 0);
  std::vector<std::thread> threads;
  for (size_t t = 0; t < names.size(); ++t) {
    threads.emplace_back([&, t] {
      try {
        for (int round = 0; round < 8; ++round) {
          BagReader reader(FixturePath(names[t]));
          records::DepthFrame f;
          while (reader.Next(&f)) ++frames[t];
        }
      } catch (const std::exception& e) {
        errors[t] = e.what();
      }
    });
  }
  for (auto& th : threads) th.join();
  for (size_t t = 0; t < names.size(); ++t) {
    EXPECT_EQ(errors[t], "") << names[t];
    EXPECT_GT(frames[t], 0) << names[t];
  }
}

TEST(PresetName, FollowsTheD455Numbering) {
  EXPECT_EQ(camera::PresetName(3), "HA");
  EXPECT_EQ(camera::PresetName(4), "HD");
  EXPECT_EQ(camera::PresetName(0), "Custom");
  EXPECT_EQ(camera::PresetName(9), "preset 9");
  EXPECT_EQ(camera::PresetName(3.5), "preset 3.5");
}

// ---------------------------------------------------------------- BagWriter round trips

std::uint16_t Pixel(int u, int v, int i) {
  if ((u * 3 + v + i) % 17 == 0) return 0;
  return static_cast<std::uint16_t>((11 * u + 97 * v + 4093 * i) % 65535 + 1);
}

BagWriterConfig TestConfig(int width, int height, bool lz4, double units_m) {
  BagWriterConfig c;
  c.intrinsics.width = width;
  c.intrinsics.height = height;
  c.intrinsics.fx = 0.6 * width;
  c.intrinsics.fy = 0.61 * width;
  c.intrinsics.ppx = width / 2.0 + 0.3;
  c.intrinsics.ppy = height / 2.0 - 0.2;
  c.intrinsics.model = camera::Distortion::kInverseBrownConrady;
  c.intrinsics.coeffs = {0.1, -0.2, 0.003, -0.004, 0.05};
  c.depth_units_m = units_m;
  c.compress_lz4 = lz4;
  c.options = {{"Visual_Preset", 3}, {"Emitter_Enabled", 1}, {"Laser_Power", 150}};
  c.device = {{"Name", "Intel RealSense D455"}, {"Serial Number", "007"}};
  return c;
}

records::DepthFrame TestFrame(int width, int height, int i, double units_m) {
  records::DepthFrame f;
  f.width = width;
  f.height = height;
  f.depth_units_m = units_m;
  f.frame_number = 1000 + i;
  f.timestamp_ms = 5999.9999996 + 33.36 * i;  // the first rounds up to a whole second
  f.counts.resize(static_cast<std::size_t>(width) * height);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) f.counts[v * width + u] = Pixel(u, v, i);
  return f;
}

std::string WriteTestBag(const std::string& path, int width, int height, int frames, bool lz4,
                         double units_m) {
  BagWriter writer(path, TestConfig(width, height, lz4, units_m));
  for (int i = 0; i < frames; ++i) writer.Write(TestFrame(width, height, i, units_m));
  writer.Close();
  return path;
}

class WriterRoundTrip : public ::testing::TestWithParam<bool> {};

TEST_P(WriterRoundTrip, ReadsBackEveryFrameAndSetting) {
  const bool lz4 = GetParam();
  TempDir dir;
  const int w = 320, h = 240, n = 9;  // several chunks
  const std::string path = WriteTestBag(dir.File("w.bag"), w, h, n, lz4, 0.0001);
  EXPECT_FALSE(fs::exists(path + ".part"));
  BagReader reader(path);
  const BagInfo& info = reader.info();
  const BagWriterConfig c = TestConfig(w, h, lz4, 0.0001);
  EXPECT_EQ(info.compressed, lz4);
  EXPECT_EQ(info.depth_frames, static_cast<std::uint64_t>(n));
  EXPECT_EQ(info.depth_intrinsics.width, w);
  EXPECT_EQ(info.depth_intrinsics.fx, c.intrinsics.fx);
  EXPECT_EQ(info.depth_intrinsics.ppy, c.intrinsics.ppy);
  EXPECT_EQ(info.depth_intrinsics.model, c.intrinsics.model);
  EXPECT_EQ(info.depth_intrinsics.coeffs, c.intrinsics.coeffs);
  EXPECT_EQ(info.depth_units_m, static_cast<double>(0.0001f));
  EXPECT_EQ(info.options.at("Visual_Preset"), 3.0);
  EXPECT_EQ(info.options.at("Emitter_Enabled"), 1.0);
  EXPECT_EQ(info.options.at("Laser_Power"), 150.0);
  EXPECT_EQ(info.options.at("Depth_Units"), static_cast<double>(0.0001f));
  EXPECT_EQ(info.device.at("Serial Number"), "007");
  EXPECT_NEAR(info.first_timestamp_ms, TestFrame(w, h, 0, 0.0001).timestamp_ms, 1e-3);
  EXPECT_NEAR(info.last_timestamp_ms, TestFrame(w, h, n - 1, 0.0001).timestamp_ms, 1e-3);
  records::DepthFrame f;
  int i = 0;
  for (; reader.Next(&f); ++i) {
    const records::DepthFrame want = TestFrame(w, h, i, 0.0001);
    EXPECT_EQ(f.frame_number, want.frame_number);
    EXPECT_NEAR(f.timestamp_ms, want.timestamp_ms, 1e-3);
    EXPECT_EQ(f.counts, want.counts) << i;
    EXPECT_EQ(f.depth_units_m, static_cast<double>(0.0001f));
  }
  EXPECT_EQ(i, n);
}

INSTANTIATE_TEST_SUITE_P(Compression, WriterRoundTrip, ::testing::Values(false, true),
                         [](const auto& p) { return p.param ? "lz4" : "none"; });

TEST(BagWriter, BagsReadByRosbagStorage) {
  TempDir dir;
  for (bool lz4 : {false, true}) {
    const std::string path = WriteTestBag(dir.File("w.bag"), 64, 48, 4, lz4, 0.001);
    rosbag::Bag bag(path, rosbag::bagmode::Read);
    rosbag::View view(bag, rosbag::TopicQuery("/device_0/sensor_0/Depth_0/image/data"));
    int i = 0;
    for (const rosbag::MessageInstance& m : view) {
      const sensor_msgs::Image::ConstPtr image = m.instantiate<sensor_msgs::Image>();
      ASSERT_TRUE(image);
      EXPECT_EQ(image->encoding, "mono16");
      EXPECT_EQ(image->header.frame_id, "1");
      const records::DepthFrame want = TestFrame(64, 48, i, 0.001);
      ASSERT_EQ(image->data.size(), want.counts.size() * 2);
      EXPECT_EQ(std::memcmp(image->data.data(), want.counts.data(), image->data.size()), 0);
      ++i;
    }
    EXPECT_EQ(i, 4);
  }
}

// Bags from before librealsense put depth units in each frame: the Depth_Units option is used.
TEST(BagWriter, FramesWithoutTheirOwnUnitsUseTheDepthUnitsOption) {
  TempDir dir;
  const std::string path = dir.File("w.bag");
  {
    BagWriter writer(path, TestConfig(64, 48, false, 0.001));  // Depth_Units option: 0.001
    for (int i = 0; i < 3; ++i) writer.Write(TestFrame(64, 48, i, 0.0001));  // frames: 0.0001
    writer.Close();
  }
  {
    BagReader reader(path);
    records::DepthFrame f;
    ASSERT_TRUE(reader.Next(&f));
    EXPECT_EQ(f.depth_units_m, static_cast<double>(0.0001f));  // the frame's own units win
  }
  std::string bytes = ReadBytes(path);
  // header.frame_id "1" (after seq and stamp) marks the units float: make it "0".
  const std::string marked("\x01\x00\x00\x00" "1" "\x30\x00\x00\x00", 9);  // then height 48
  ASSERT_EQ(Replace(&bytes, marked, std::string("\x01\x00\x00\x00" "0" "\x30\x00\x00\x00", 9)),
            3u);
  WriteBytes(path, bytes);
  BagReader reader(path);
  EXPECT_EQ(reader.info().depth_units_m, static_cast<double>(0.001f));
  records::DepthFrame f;
  int n = 0;
  for (; reader.Next(&f); ++n) {
    EXPECT_EQ(f.depth_units_m, static_cast<double>(0.001f));
    EXPECT_EQ(f.counts, TestFrame(64, 48, n, 0.0001).counts);
  }
  EXPECT_EQ(n, 3);
}

// A recording abandoned by an error (the writer destroyed without Close) leaves no file, neither
// under its name nor as PATH.part.
TEST(BagWriter, AnAbandonedRecordingLeavesNoFile) {
  TempDir dir;
  const std::string path = dir.File("abandoned.bag");
  try {
    BagWriter writer(path, TestConfig(64, 48, false, 0.001));
    writer.Write(TestFrame(64, 48, 0, 0.001));
    ASSERT_TRUE(std::filesystem::exists(path + ".part"));
    throw std::runtime_error("render failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(path + ".part"));
}

TEST(BagWriter, RefusesFramesOfAnotherSizeAndBadConfig) {
  TempDir dir;
  BagWriter writer(dir.File("w.bag"), TestConfig(64, 48, false, 0.001));
  try {
    writer.Write(TestFrame(32, 48, 0, 0.001));
    ADD_FAILURE() << "wrote a frame of the wrong size";
  } catch (const BagError& e) {
    EXPECT_EQ(e.kind(), Kind::kWrite);
  }
  BagWriterConfig bad = TestConfig(64, 48, false, 0.001);
  bad.depth_units_m = 0.0;
  EXPECT_THROW(BagWriter(dir.File("bad.bag"), bad), BagError);
  EXPECT_THROW(BagWriter(dir.File("no/such/dir/x.bag"), TestConfig(64, 48, false, 0.001)),
               BagError);
}

// ---------------------------------------------------------------- bad input

TEST(BadInput, MissingPath) {
  TempDir dir;
  EXPECT_EQ(ExpectBagError(dir.File("nothing_here.bag")), Kind::kNotFound);
}

TEST(BadInput, Directory) {
  TempDir dir;
  EXPECT_EQ(ExpectBagError(dir.File("")), Kind::kNotAFile);
}

TEST(BadInput, EmptyFile) {
  TempDir dir;
  WriteBytes(dir.File("empty.bag"), "");
  EXPECT_EQ(ExpectBagError(dir.File("empty.bag")), Kind::kEmpty);
}

TEST(BadInput, NotABag) {
  TempDir dir;
  WriteBytes(dir.File("text.bag"), "bag,distance_m,angle_deg,light\nx.bag,4,0,daylight\n");
  EXPECT_EQ(ExpectBagError(dir.File("text.bag")), Kind::kNotABag);
  WriteBytes(dir.File("short.bag"), "#ROS");
  EXPECT_EQ(ExpectBagError(dir.File("short.bag")), Kind::kNotABag);
  WriteBytes(dir.File("v12.bag"), "#ROSBAG V1.2\n" + std::string(100, '\0'));
  EXPECT_EQ(ExpectBagError(dir.File("v12.bag")), Kind::kNotABag);
  WriteBytes(dir.File("magic_only.bag"), "#ROSBAG V2.0\n");
  EXPECT_EQ(ExpectBagError(dir.File("magic_only.bag")), Kind::kTruncated);
}

TEST(BadInput, TruncatedInTheMiddleOfAChunk) {
  TempDir dir;
  for (const char* name : {"d455_depth_1mm.bag", "d455_depth_100um_lz4.bag"}) {
    const std::string bytes = ReadBytes(FixturePath(name));
    const std::string cut = dir.File(std::string("cut_") + name);
    WriteBytes(cut, bytes.substr(0, bytes.size() / 2));
    EXPECT_EQ(ExpectBagError(cut), Kind::kTruncated) << name;
  }
}

TEST(BadInput, TruncatedBagGivesTheFramesBeforeTheDamageWhenAsked) {
  TempDir dir;
  const int w = 320, h = 240, n = 9;
  for (bool lz4 : {false, true}) {
    const std::string whole = WriteTestBag(dir.File("whole.bag"), w, h, n, lz4, 0.001);
    const std::string bytes = ReadBytes(whole);
    const std::string cut = dir.File("cut.bag");
    WriteBytes(cut, bytes.substr(0, bytes.size() * 9 / 10));  // inside the second chunk
    EXPECT_EQ(ExpectBagError(cut), Kind::kTruncated);

    BagReader reader(cut, ReadOptions{true});
    EXPECT_FALSE(reader.info().indexed);
    records::DepthFrame f;
    int i = 0;
    for (; reader.Next(&f); ++i) EXPECT_EQ(f.counts, TestFrame(w, h, i, 0.001).counts) << i;
    EXPECT_GT(i, 0) << "lz4 " << lz4;
    EXPECT_LT(i, n) << "lz4 " << lz4;
    EXPECT_EQ(static_cast<std::uint64_t>(i), reader.info().depth_frames);
    EXPECT_NE(reader.damage().find(cut), std::string::npos) << reader.damage();
  }
}

TEST(BadInput, TruncatedRecordingGivesItsFirstFramesWhenAsked) {
  TempDir dir;
  const Truth truth("d455_depth_1mm.bag");
  const std::string bytes = ReadBytes(FixturePath("d455_depth_1mm.bag"));
  const std::string cut = dir.File("cut.bag");
  // Cut inside the pixels of the last frame.
  WriteBytes(cut, bytes.substr(0, bytes.rfind("mono16") + 100));
  BagReader reader(cut, ReadOptions{true});
  records::DepthFrame f;
  std::size_t i = 0;
  for (; reader.Next(&f); ++i) {
    const auto pixels = truth.node["frames"][i]["pixels"].as<std::vector<int>>();
    EXPECT_TRUE(std::equal(pixels.begin(), pixels.end(), f.counts.begin())) << i;
  }
  EXPECT_GT(i, 0u);
  EXPECT_LT(i, truth.node["frames"].size());
  EXPECT_FALSE(reader.damage().empty());
}

TEST(BadInput, CorruptedCompressedChunk) {
  TempDir dir;
  std::string bytes = ReadBytes(FixturePath("d455_depth_100um_lz4.bag"));
  for (std::size_t k = 0; k < 64; ++k) bytes[bytes.size() / 2 + k] = static_cast<char>(0xA5);
  const std::string bad = dir.File("corrupt.bag");
  WriteBytes(bad, bytes);
  EXPECT_EQ(ExpectBagError(bad), Kind::kCorrupt);
  // Asking for a partial read gives no frame from the damaged chunk, and no crash.
  try {
    BagReader reader(bad, ReadOptions{true});
    records::DepthFrame f;
    while (reader.Next(&f)) {
    }
    EXPECT_FALSE(reader.damage().empty());
  } catch (const BagError& e) {
    EXPECT_EQ(e.kind(), Kind::kCorrupt);
  }
}

TEST(BadInput, CorruptedUncompressedChunk) {
  TempDir dir;
  const std::string original = ReadBytes(FixturePath("d455_depth_1mm.bag"));
  // A chunk header that no longer names a compression.
  std::string bytes = original;
  ASSERT_EQ(Replace(&bytes, "compression=none", "compression=zzzz"), 1u);
  WriteBytes(dir.File("a.bag"), bytes);
  EXPECT_EQ(ExpectBagError(dir.File("a.bag")), Kind::kCorrupt);
  // A message record inside the chunk whose header length runs past the chunk.
  bytes = original;
  const std::string image_conn_op = "op=\x02";
  std::size_t at = bytes.rfind(image_conn_op);
  ASSERT_NE(at, std::string::npos);
  at = bytes.rfind("conn=", at);  // fields: conn, op, time; the header length is 4+9 bytes earlier
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at - 8, 4, "\xff\xff\xff\x7f", 4);
  WriteBytes(dir.File("b.bag"), bytes);
  EXPECT_EQ(ExpectBagError(dir.File("b.bag")), Kind::kCorrupt);
}

TEST(BadInput, NoDepthStream) {
  TempDir dir;
  std::string bytes = ReadBytes(FixturePath("d455_depth_color_imu.bag"));
  ASSERT_GT(Replace(&bytes, "/Depth_0/", "/Dapth_0/"), 0u);
  WriteBytes(dir.File("nodepth.bag"), bytes);
  EXPECT_EQ(ExpectBagError(dir.File("nodepth.bag")), Kind::kNoDepthStream);
  try {
    BagReader reader(dir.File("nodepth.bag"));
  } catch (const BagError& e) {
    EXPECT_NE(std::string(e.what()).find("Color_0"), std::string::npos) << e.what();
  }
}

TEST(BadInput, RecordingWithoutFrames) {
  TempDir dir;
  BagWriter(dir.File("empty_recording.bag"), TestConfig(64, 48, false, 0.001)).Close();
  EXPECT_EQ(ExpectBagError(dir.File("empty_recording.bag")), Kind::kNoDepthStream);
}

TEST(BadInput, DepthStreamInAnotherEncoding) {
  TempDir dir;
  std::string bytes = ReadBytes(FixturePath("d455_depth_1mm.bag"));
  ASSERT_GT(Replace(&bytes, "mono16", "yuv422"), 0u);
  WriteBytes(dir.File("yuv.bag"), bytes);
  EXPECT_EQ(ExpectBagError(dir.File("yuv.bag")), Kind::kBadEncoding);
  // Only the frames in another encoding: caught when the frames are read.
  bytes = ReadBytes(FixturePath("d455_depth_1mm.bag"));
  const std::string frame_encoding = std::string("\x06\x00\x00\x00mono16\x00\x80", 12);
  ASSERT_GT(Replace(&bytes, frame_encoding, std::string("\x06\x00\x00\x00yuv422\x00\x80", 12)), 0u);
  WriteBytes(dir.File("frames.bag"), bytes);
  EXPECT_EQ(ExpectBagError(dir.File("frames.bag")), Kind::kBadEncoding);
}

// Positions of the message offsets in the index data records after each chunk (entries of 12
// bytes: sec, nsec, offset of the message in the chunk).
std::vector<std::size_t> IndexDataOffsets(const std::string& bytes) {
  auto u32 = [&](std::size_t p) {
    std::uint32_t v;
    std::memcpy(&v, bytes.data() + p, 4);
    return v;
  };
  std::vector<std::size_t> at;
  std::size_t pos = 13;  // after "#ROSBAG V2.0\n"
  while (pos + 8 <= bytes.size()) {
    const std::uint32_t header = u32(pos);
    const std::size_t data_at = pos + 8 + header;
    const std::uint32_t data = u32(pos + 4 + header);
    if (bytes.substr(pos + 4, header).find(std::string("op=\x04", 4)) != std::string::npos)
      for (std::size_t k = 0; k + 12 <= data; k += 12) at.push_back(data_at + k + 8);
    pos = data_at + data;
  }
  return at;
}

// rosbag reads each message at the offset the index data gives, without checking it. The check
// made before rosbag opens the bag finds a damaged offset: in an uncompressed chunk any offset
// that is not the indexed message's record; in a compressed chunk (which it does not decompress)
// only an offset outside the chunk.
TEST(BadInput, DamagedMessageOffsetsInTheIndex) {
  TempDir dir;
  const std::string path = dir.File("offsets.bag");
  for (const char* name : {"d455_depth_1mm.bag", "d455_depth_100um_lz4.bag"}) {
    const bool lz4 = std::string(name).find("lz4") != std::string::npos;
    const std::string original = ReadBytes(FixturePath(name));
    const std::vector<std::size_t> offsets = IndexDataOffsets(original);
    ASSERT_GT(offsets.size(), 10u) << name;
    int runs = 0, errors = 0;
    const std::vector<std::int64_t> deltas =
        lz4 ? std::vector<std::int64_t>{1 << 20, 1ll << 31}
            : std::vector<std::int64_t>{1, 3, -1, 1 << 20};
    for (std::size_t at : offsets) {
      for (std::int64_t delta : deltas) {
        std::string bytes = original;
        std::uint32_t v;
        std::memcpy(&v, &bytes[at], 4);
        v = static_cast<std::uint32_t>(static_cast<std::int64_t>(v) + delta);
        std::memcpy(&bytes[at], &v, 4);
        WriteBytes(path, bytes);
        ++runs;
        try {
          BagReader reader(path);
          records::DepthFrame f;
          while (reader.Next(&f)) {
          }
        } catch (const BagError& e) {
          ++errors;
          EXPECT_EQ(e.kind(), Kind::kCorrupt) << e.what();
        }
      }
    }
    EXPECT_EQ(errors, runs) << name;
  }
}

// Random damage to real bags: every outcome is frames or a BagError, never a crash or a hang.
TEST(BadInput, RandomDamageNeverCrashes) {
  TempDir dir;
  std::mt19937 rng(20240613);
  const std::string path = dir.File("fuzz.bag");
  int errors = 0, runs = 0;
  for (const char* name : {"d455_depth_1mm.bag", "d455_depth_100um_lz4.bag",
                           "d455_depth_color_imu_lz4.bag"}) {
    const std::string original = ReadBytes(FixturePath(name));
    for (int trial = 0; trial < 60; ++trial) {
      std::string bytes = original;
      const int kind = trial % 3;
      if (kind == 0) {
        bytes.resize(std::uniform_int_distribution<std::size_t>(0, bytes.size() - 1)(rng));
      } else {
        const int flips = kind == 1 ? 1 : 16;
        for (int k = 0; k < flips; ++k)
          bytes[std::uniform_int_distribution<std::size_t>(0, bytes.size() - 1)(rng)] =
              static_cast<char>(rng());
      }
      WriteBytes(path, bytes);
      for (bool partial : {false, true}) {
        ++runs;
        try {
          BagReader reader(path, ReadOptions{partial});
          records::DepthFrame f;
          int frames = 0;
          while (reader.Next(&f) && frames < 1000) ++frames;
        } catch (const BagError& e) {
          ++errors;
          EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
        }
      }
    }
  }
  EXPECT_GT(errors, 0);
  EXPECT_EQ(runs, 360);
}

}  // namespace
}  // namespace depthbias::io
