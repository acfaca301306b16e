// diagnose_gap and simulate --calibrate-to run as a user runs them: bad input stops with one
// line naming the file (exit 2), a diagnosis writes gap.json and report.md with the documented
// keys, and the calibration writes a sensor file the simulator reads back.
#include <gtest/gtest.h>

#include <algorithm>
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
