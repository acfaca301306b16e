// diagnose_gap and simulate --calibrate-to run as a user runs them: bad input stops with one
// line naming the file (exit 2), a diagnosis writes gap.json and report.md with the documented
// keys, simulations kept between runs give the same outputs, and the calibration writes a
// sensor file the simulator reads back.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/atomic_file.h"
#include "io/metrics_csv.h"
#include "sim/config_yaml.h"
#include "support/tools.h"

namespace depthbias {
namespace {

namespace fs = std::filesystem;

using test_support::Bin;
using test_support::ReadFile;
using test_support::RunShell;

fs::path Dir(const std::string& name) {
  const fs::path d = fs::path(DEPTHBIAS_BINARY_DIR) / "test_tmp" / ("gap_apps_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Runs a command from the source tree; its exit status (stderr in *err).
int RunCommand(const std::string& args, const fs::path& dir, std::string* err = nullptr) {
  const auto r = RunShell("cd " + std::string(DEPTHBIAS_SOURCE_DIR) + " && " + args, dir);
  if (err) *err = r.err;
  return r.code;
}

const std::string kArticle = DEPTHBIAS_SOURCE_DIR "/config/data/paper_d455_outdoor.csv";

// The article's rows of one scenario (32; 16 from 12 m on), as a table of its own.
fs::path OneScenario(const fs::path& dir, double from_m = 0) {
  auto rows = io::ReadMetricsCsv(kArticle);
  std::vector<records::PanelMetrics> keep;
  for (const auto& r : rows)
    if (r.light == "sunset" && r.preset == "HD" && r.distance_m >= from_m) keep.push_back(r);
  const fs::path out = dir / "sunset_hd.csv";
  io::WriteMetricsCsv(out.string(), keep);
  return out;
}

TEST(DiagnoseGapApp, BadInputStopsWithOneLineNamingTheFile) {
  const fs::path d = Dir("bad");
  std::ofstream(d / "empty.csv") << "";
  std::ofstream(d / "header.csv")
      << "bag,light,emitter,preset,distance_m,angle_deg,frames,mean_m,median_m,plane_std_m,"
         "hole_rate_pct,valid_pct\n";
  std::ofstream(d / "nocol.csv") << "bag,light,emitter,preset,distance_m\nx,daylight,on,HA,4\n";
  std::ofstream(d / "nan.csv")
      << "bag,light,emitter,preset,distance_m,angle_deg,frames,mean_m,median_m,plane_std_m,"
         "hole_rate_pct,valid_pct\nx,daylight,on,HA,4,0,30,4.0,4.0,,50,50\n";
  for (const char* name : {"empty.csv", "header.csv", "nocol.csv", "nan.csv", "missing.csv"}) {
    std::string err;
    const fs::path in = d / name;
    EXPECT_EQ(RunCommand(Bin("diagnose_gap") + " --real " + in.string() + " --out " +
                      (d / "out").string(),
                  d, &err),
              2)
        << name;
    EXPECT_NE(err.find(name), std::string::npos) << name << ": " << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
  EXPECT_FALSE(fs::exists(d / "out" / "gap.json"));
  std::string err;
  EXPECT_EQ(RunCommand(Bin("diagnose_gap") + " --real " + kArticle + " --out " +
                           (d / "o").string() +
                    " --holdout angle",
                d, &err),
            2);
  EXPECT_NE(err.find("holdout"), std::string::npos) << err;
  EXPECT_EQ(RunCommand(Bin("diagnose_gap") + " --real " + kArticle, d, &err), 2);
  EXPECT_EQ(RunCommand(Bin("diagnose_gap") + " --help", d), 0);
}

TEST(DiagnoseGapApp, WritesGapJsonAndReport) {
  const fs::path d = Dir("run");
  const fs::path in = OneScenario(d);
  std::string err;
  ASSERT_EQ(RunCommand(Bin("diagnose_gap") + " --real " + in.string() + " --out " +
                    (d / "out").string() +
                    " --candidates disparity_offset,edge_mixing --frames 4 --threads 2",
                d, &err),
            0)
      << err;
  const std::string json = ReadFile(d / "out" / "gap.json");
  for (const char* key : {"\"baseline_gap\"", "\"localization\"", "\"effects\"", "\"selected\"",
                          "\"confounded\"", "\"remaining_gap\"", "\"cells\"", "\"delta_bic\"",
                          "\"shrink_in_sample_pct\"", "\"shrink_heldout_pct\"", "\"ci95\"",
                          "\"params\"", "\"noise_method\"", "\"placement\"", "\"emitter\"",
                          "\"shrink_simulated_pct\"", "\"shrink_heldout_nested_pct\"",
                          "\"unexplained\"", "\"ambiguous\"", "\"detection_limits\"",
                          "\"simulated_sq_per_metric\""})
    EXPECT_NE(json.find(key), std::string::npos) << key;
  const std::string md = ReadFile(d / "out" / "report.md");
  for (const char* part : {"## 1. The gap", "## 2. Where", "## 3. Which effect", "## 4. How far",
                           "## 5. What is left", "## What this table cannot see"})
    EXPECT_NE(md.find(part), std::string::npos) << part;
  EXPECT_NE(ReadFile(d / "stdout.txt").find("how far:"), std::string::npos);
  // Never writes over an input.
  EXPECT_EQ(RunCommand(Bin("diagnose_gap") + " --real " + (d / "out" / "gap.json").string() +
                           " --out " +
                    (d / "out").string(),
                d, &err),
            2);
}

// --cache DIR: the simulations kept and taken back give the outputs of a run without it, byte
// for byte; an entry altered with its checksum made good is read (what is in the folder is
// what a run uses), one altered without is noted, simulated again and written over; another
// seed is another entry; a file given as the folder stops the run.
TEST(DiagnoseGapApp, KeptSimulationsGiveTheSameOutputs) {
  const fs::path d = Dir("cache");
  const fs::path in = OneScenario(d);
  const fs::path cache = d / "kept";
  auto run = [&](const std::string& out, const std::string& more, std::string* err) {
    return RunCommand(Bin("diagnose_gap") + " --real " + in.string() + " --out " +
                          (d / out).string() +
                          " --candidates disparity_offset,edge_mixing --frames 4 --threads 2" +
                          more,
                      d, err);
  };
  std::string err;
  ASSERT_EQ(run("plain", "", &err), 0) << err;
  ASSERT_EQ(run("cold", " --cache " + cache.string(), &err), 0) << err;
  EXPECT_EQ(err.find("note"), std::string::npos) << err;
  std::vector<fs::path> entries;
  for (const auto& e : fs::directory_iterator(cache)) entries.push_back(e.path());
  ASSERT_EQ(entries.size(), 1u);
  ASSERT_EQ(run("warm", " --cache " + cache.string(), &err), 0) << err;
  EXPECT_EQ(err.find("note"), std::string::npos) << err;
  for (const char* file : {"gap.json", "report.md"})
    for (const char* out : {"cold", "warm"})
      EXPECT_EQ(ReadFile(d / out / file), ReadFile(d / "plain" / file)) << out << "/" << file;

  // A value altered and the checksum (FNV-1a 64 of every byte before it, its last 8 bytes) made
  // good: the run reads it, so its outputs move.
  const std::string bytes = ReadFile(entries[0]);
  ASSERT_GT(bytes.size(), 200u);
  auto with_checksum = [](std::string b) {
    std::uint64_t h = 14695981039346656037ull;
    for (size_t i = 0; i + 8 < b.size(); ++i) {
      h ^= static_cast<unsigned char>(b[i]);
      h *= 1099511628211ull;
    }
    std::memcpy(&b[b.size() - 8], &h, 8);
    return b;
  };
  // The first cell's simulated median bias, the first value after the format's line, the key
  // (its length, then its text) and the base's count, moved by 1 m.
  const size_t magic = bytes.find('\n') + 1;
  std::uint64_t key_length = 0;
  std::memcpy(&key_length, bytes.data() + magic, 8);
  const size_t first = magic + 8 + key_length + 8;
  ASSERT_LT(first + 8, bytes.size());
  double value = 0;
  std::memcpy(&value, bytes.data() + first, 8);
  value += 1.0;
  std::string altered = bytes;
  std::memcpy(&altered[first], &value, 8);
  io::WriteFileAtomic(entries[0].string(), with_checksum(altered));
  ASSERT_EQ(run("altered", " --cache " + cache.string(), &err), 0) << err;
  EXPECT_NE(ReadFile(d / "altered" / "gap.json"), ReadFile(d / "plain" / "gap.json"));
  // Altered without: noted with the file and the reason, simulated again, written over.
  io::WriteFileAtomic(entries[0].string(), altered);
  ASSERT_EQ(run("noted", " --cache " + cache.string(), &err), 0) << err;
  EXPECT_NE(err.find(entries[0].string()), std::string::npos) << err;
  EXPECT_NE(err.find("checksum"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_EQ(ReadFile(d / "noted" / "gap.json"), ReadFile(d / "plain" / "gap.json"));
  EXPECT_EQ(ReadFile(entries[0]), bytes);
  // Another seed, another entry.
  ASSERT_EQ(run("seed2", " --seed 2 --cache " + cache.string(), &err), 0) << err;
  EXPECT_EQ(std::distance(fs::directory_iterator(cache), fs::directory_iterator()), 2);
  // A file as the folder: one line naming it, exit 2, nothing written.
  EXPECT_EQ(run("file", " --cache " + (d / "sunset_hd.csv").string(), &err), 2);
  EXPECT_NE(err.find("sunset_hd.csv"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_FALSE(fs::exists(d / "file" / "gap.json"));
}

TEST(SimulateApp, CalibrateToWritesASensorTheSimulatorReads) {
  const fs::path d = Dir("calibrate");
  const fs::path in = OneScenario(d, 12);
  const fs::path out = d / "sensor.yaml";
  std::string err;
  ASSERT_EQ(RunCommand(Bin("simulate") + " --protocol config/protocol_paper.yaml --sensor builtin "
                    "--calibrate-to " + in.string() + " --frames 3 --out " + out.string(),
                d, &err),
            0)
      << err;
  sim::SensorParams s;
  std::string why;
  ASSERT_TRUE(sim::ParseSensorYaml(ReadFile(out), &s, &why)) << why;
  bool found = false;
  const sim::ScenarioParams sc = s.Scenario("sunset", "HD", &found);
  EXPECT_TRUE(found);
  EXPECT_GT(sc.sigma_d_px, 0.01);
  EXPECT_NE(ReadFile(out).find("calibration:"), std::string::npos);
}

}  // namespace
}  // namespace depthbias
