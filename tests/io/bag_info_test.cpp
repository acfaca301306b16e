// The bag_info app on librealsense-written fixtures and on a missing file: its --json output
// carries the truth the fixtures were recorded with; an unreadable bag gives {file, error} and
// a non-zero exit.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct AppRun {
  int status = -1;
  std::vector<std::string> lines;
};

AppRun RunBagInfo(const std::string& args) {
  const char* bin = std::getenv("DEPTHBIAS_BIN");
  EXPECT_NE(bin, nullptr) << "DEPTHBIAS_BIN not set";
  AppRun run;
  if (!bin) return run;
  const std::string cmd = std::string(bin) + "/bag_info " + args + " 2>/dev/null";
  FILE* p = popen(cmd.c_str(), "r");
  EXPECT_NE(p, nullptr);
  if (!p) return run;
  std::string out;
  char buf[4096];
  for (std::size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  run.status = pclose(p);
  std::istringstream s(out);
  for (std::string line; std::getline(s, line);) run.lines.push_back(line);
  return run;
}

std::string Bag(const std::string& name) {
  return std::string(DEPTHBIAS_TEST_DATA) + "/bags/" + name;
}

TEST(BagInfoApp, JsonCarriesTheRecordedTruth) {
  const std::vector<std::string> names = {"d455_depth_1mm", "d455_depth_100um_lz4",
                                          "d455_depth_color_imu_lz4"};
  std::string args = "--json";
  for (const auto& n : names) args += " " + Bag(n + ".bag");
  const AppRun run = RunBagInfo(args);
  ASSERT_TRUE(WIFEXITED(run.status));
  EXPECT_EQ(WEXITSTATUS(run.status), 0);
  ASSERT_EQ(run.lines.size(), names.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    const YAML::Node truth = YAML::LoadFile(Bag(names[i] + ".truth.json"));
    const YAML::Node j = YAML::Load(run.lines[i]);
    EXPECT_EQ(j["file"].as<std::string>(), Bag(names[i] + ".bag"));
    const YAML::Node in = j["depth"]["intrinsics"];
    for (const char* k : {"width", "height"})
      EXPECT_EQ(in[k].as<int>(), truth["intrinsics"][k].as<int>()) << k;
    for (const char* k : {"fx", "fy", "ppx", "ppy"})
      EXPECT_FLOAT_EQ(in[k].as<float>(), truth["intrinsics"][k].as<float>()) << k;
    ASSERT_EQ(in["coeffs"].size(), 5u);
    for (int c = 0; c < 5; ++c)
      EXPECT_FLOAT_EQ(in["coeffs"][c].as<float>(), truth["intrinsics"]["coeffs"][c].as<float>());
    EXPECT_FALSE(in["model"].as<std::string>().empty());
    EXPECT_FLOAT_EQ(j["depth"]["depth_units"].as<float>(), truth["depth_units"].as<float>());
    EXPECT_EQ(j["depth"]["frames"].as<std::size_t>(), truth["frames"].size());
    for (const auto& kv : truth["options"]) {
      const std::string name = kv.first.as<std::string>();
      EXPECT_FLOAT_EQ(j["options"][name].as<float>(), kv.second.as<float>()) << name;
    }
    EXPECT_EQ(j["device"]["name"].as<std::string>(), truth["device"]["Name"].as<std::string>());
    EXPECT_EQ(j["device"]["serial"].as<std::string>(),
              truth["device"]["Serial Number"].as<std::string>());
  }
}

TEST(BagInfoApp, UnreadableBagGivesAnErrorObjectAndNonZeroExit) {
  const std::string missing = std::string(DEPTHBIAS_BINARY_DIR) + "/no_such_recording.bag";
  const AppRun run = RunBagInfo(Bag("d455_depth_1mm.bag") + " " + missing + " --json");
  ASSERT_TRUE(WIFEXITED(run.status));
  EXPECT_NE(WEXITSTATUS(run.status), 0);
  ASSERT_EQ(run.lines.size(), 2u);
  EXPECT_TRUE(YAML::Load(run.lines[0])["depth"]);
  const YAML::Node err = YAML::Load(run.lines[1]);
  EXPECT_EQ(err["file"].as<std::string>(), missing);
  EXPECT_NE(err["error"].as<std::string>().find(missing), std::string::npos);
}

TEST(BagInfoApp, TextListsStreamsOptionsAndDevice) {
  const AppRun run = RunBagInfo(Bag("d455_depth_color_imu.bag"));
  ASSERT_TRUE(WIFEXITED(run.status));
  EXPECT_EQ(WEXITSTATUS(run.status), 0);
  std::string all;
  for (const auto& l : run.lines) all += l + "\n";
  for (const char* want : {"Depth_0", "Color_0", "Infrared_1", "Accel_0", "Visual_Preset = 4",
                           "Emitter_Enabled = 1", "Serial Number: 213522250123",
                           "depth units: 0.0001 m", "frames:      3"})
    EXPECT_NE(all.find(want), std::string::npos) << want << "\n" << all;
}

}  // namespace
