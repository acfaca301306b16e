// Every tool that reads a metrics table refuses one whose header lacks a column that ok rows
// need, in one line naming the file and the column, and writes nothing (exit 2).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "support/tools.h"
#include "test_dir.h"

namespace depthbias::io {
namespace {

namespace fs = std::filesystem;
using test_support::Bin;
using test_support::RunShell;

// The input that fuzz_metrics_csv first tripped on: median_m misspelled, an ok row after it.
const char* kMisspelledMedian =
    "bag,light,emitter,preset,distance_m,angle_deg,frames,mean_m,medain_m,plane_std_m,"
    "hole_rate_pct,valid_pct,status,message\n"
    "x.bag,daylight,on,HA,4,0,30,4.02,4.01,0.01,2,98,ok,\n"
    "y.bag,daylight,off,HA,4,0,30,4.03,4.02,0.01,3,97,ok,\n";

void ExpectRefusedNamingFileAndColumn(const std::string& command, const fs::path& dir,
                                      const fs::path& table, const fs::path& out) {
  const auto r = RunShell(command, dir);
  EXPECT_EQ(r.code, 2) << command << "\n" << r.err;
  EXPECT_NE(r.err.find(table.string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("'median_m'"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(out)) << out;
}

TEST(MetricsCsvTools, MissingRequiredColumnIsRefusedByEveryReader) {
  const fs::path dir = testing::FreshDir("metrics_apps");
  const fs::path table = dir / "misspelled.csv";
  std::ofstream(table) << kMisspelledMedian;
  const fs::path weights = dir / "w.yaml";
  ASSERT_EQ(RunShell(Bin("fit_bias") + " --in " DEPTHBIAS_SOURCE_DIR
                     "/config/data/paper_d455_outdoor.csv --out " + weights.string(), dir).code,
            0);

  ExpectRefusedNamingFileAndColumn(
      Bin("fit_bias") + " --in " + table.string() + " --out " + (dir / "f.yaml").string(), dir,
      table, dir / "f.yaml");
  ExpectRefusedNamingFileAndColumn(Bin("correct_depth") + " --weights " + weights.string() +
                                       " --in " + table.string() + " --out " +
                                       (dir / "c.csv").string(),
                                   dir, table, dir / "c.csv");
  ExpectRefusedNamingFileAndColumn(
      Bin("diagnose_gap") + " --real " + table.string() + " --out " + (dir / "gap").string(),
      dir, table, dir / "gap");
}

}  // namespace
}  // namespace depthbias::io
