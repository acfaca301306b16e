// diagnose_gap's input, as a user meets it: outputs checked before any work, rows the simulator
// cannot stand for left out and listed (never simulated with a guessed noise, never dropped
// silently), a table beyond the stated size refused in one line, and messages that name what
// is wrong. Each case runs the real tool on real files.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "gap/cases.h"
#include "io/atomic_file.h"
#include "io/metrics_csv.h"
#include "support/article.h"
#include "support/tools.h"

namespace depthbias {
namespace {

namespace fs = std::filesystem;

using test_support::Bin;
using test_support::ReadFile;
using test_support::RunShell;

const std::string kArticle = DEPTHBIAS_SOURCE_DIR "/config/data/paper_d455_outdoor.csv";
const std::string kFast = " --candidates disparity_offset --frames 4 --threads 2";

fs::path Dir(const std::string& name) {
  const fs::path d = fs::path(DEPTHBIAS_BINARY_DIR) / "test_tmp" / ("gap_input_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// diagnose_gap run from the source tree (its default protocol and sensor).
test_support::ToolRun Diagnose(const std::string& args, const fs::path& dir) {
  return RunShell("cd " + std::string(DEPTHBIAS_SOURCE_DIR) + " && " + Bin("diagnose_gap") +
                      " " + args,
                  dir);
}

int Lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

// The article's 32 daylight/HA rows, changed by `edit`, written to dir/name.
fs::path Table(const fs::path& dir, const std::string& name,
               void (*edit)(std::vector<records::PanelMetrics>*) = nullptr) {
  std::vector<records::PanelMetrics> keep;
  for (const auto& r : io::ReadMetricsCsv(kArticle))
    if (r.light == "daylight" && r.preset == "HA") keep.push_back(r);
  if (edit) edit(&keep);
  const fs::path out = dir / name;
  io::WriteMetricsCsv(out.string(), keep);
  return out;
}

TEST(DiagnoseGapInput, AnOutputFolderThatIsAFileOrALinkToTheInputIsRefusedBeforeAnyWork) {
  const fs::path d = Dir("out");
  const fs::path in = Table(d, "t.csv");
  const std::string before = ReadFile(in);
  std::ofstream(d / "a_file") << "not a folder\n";
  fs::create_symlink(in, d / "link_to_input");
  for (const char* out : {"a_file", "link_to_input"}) {
    const auto r = Diagnose("--real " + in.string() + " --out " + (d / out).string() + kFast, d);
    EXPECT_EQ(r.code, 2) << out << ": " << r.err;
    EXPECT_EQ(Lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find((d / out).string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("not a folder"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("filesystem error"), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "") << "a diagnosis ran before the output was checked";
  }
  EXPECT_EQ(ReadFile(in), before);
  EXPECT_EQ(ReadFile(d / "a_file"), "not a folder\n");
}

// An unknown preset, an unknown light and a row at 999 m are left out, each listed with its
// reason; rows_used counts only the rows the diagnosis used; exit 1 (outputs written, rows
// failed).
TEST(DiagnoseGapInput, UnknownPresetsLightsAndDistancesAreListedInRowsSkipped) {
  const fs::path d = Dir("skipped");
  const fs::path in = Table(d, "t.csv", [](std::vector<records::PanelMetrics>* rows) {
    records::PanelMetrics xx = (*rows)[0], foggy = (*rows)[1], far = (*rows)[2];
    xx.preset = "XX";
    xx.bag = "row_xx";
    foggy.light = "foggy";
    foggy.bag = "row_foggy";
    far.distance_m = 999;
    far.median_m = 999.2;
    far.mean_m = 999.4;
    far.bag = "row_999m";
    rows->insert(rows->end(), {xx, foggy, far});
  });
  const auto r = Diagnose("--real " + in.string() + " --out " + (d / "out").string() + kFast, d);
  ASSERT_EQ(r.code, 1) << r.err;
  const std::string json = ReadFile(d / "out" / "gap.json");
  EXPECT_NE(json.find("\"rows_used\": 32"), std::string::npos);
  const size_t at = json.find("\"rows_skipped\"");
  ASSERT_NE(at, std::string::npos);
  const std::string skipped = json.substr(at, json.find(']', at) - at);
  for (const char* what : {"row 33 (row_xx): preset 'XX' is not a D455 preset",
                           "row 34 (row_foggy): light 'foggy' with preset 'HA' is not a scenario",
                           "row 35 (row_999m): distance_m 999 is outside the sensor's range"})
    EXPECT_NE(skipped.find(what), std::string::npos) << what << " in " << skipped;
  EXPECT_NE(r.err.find("row_foggy"), std::string::npos) << r.err;
}

TEST(DiagnoseGapInput, ATableBeyondTheStatedSizeIsRefusedInOneLine) {
  const fs::path d = Dir("size");
  const fs::path in = Table(d, "big.csv", [](std::vector<records::PanelMetrics>* rows) {
    const std::vector<records::PanelMetrics> one = *rows;
    while (rows->size() <= 1024) rows->insert(rows->end(), one.begin(), one.end());
  });
  const auto r = Diagnose("--real " + in.string() + " --out " + (d / "out").string() + kFast, d);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("big.csv: 1056 rows, more than the 1024"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(d / "out"));
  const auto help = Diagnose("--help", d);
  EXPECT_NE(help.out.find("more than 1024 rows is refused"), std::string::npos) << help.out;
}

TEST(DiagnoseGapInput, MessagesNameWhatIsWrong) {
  const fs::path d = Dir("messages");
  // Every row at 79.9°: the panel is outside the field of view (not "too few pairs").
  const fs::path wide = Table(d, "wide.csv", [](std::vector<records::PanelMetrics>* rows) {
    for (auto& r : *rows) r.angle_deg = 79.9;
  });
  auto r = Diagnose("--real " + wide.string() + " --out " + (d / "out").string() + kFast, d);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("wide.csv"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("angle_deg 79.9 puts the panel's centre outside the sensor's field of "
                       "view"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("pairs"), std::string::npos) << r.err;
  // An unknown candidate is a problem with --candidates, not with the table.
  const fs::path ok = Table(d, "ok.csv");
  r = Diagnose("--real " + ok.string() + " --out " + (d / "out").string() +
                   " --candidates nosuch",
               d);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_EQ(r.err.rfind("diagnose_gap: --candidates: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("nosuch"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("ok.csv"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(d / "out"));
  // --inject-times: a list of multiples in (0, 10], with --inject-into; refused before any work.
  const std::string inject = " --cases --inject-into " + ok.string() + " --out " +
                             (d / "out").string() + " --inject-times ";
  const std::vector<std::pair<std::string, std::string>> bad_times = {
      {inject + "1,x", "--inject-times: 'x' is not a multiple in (0, 10]"},
      {inject + "0", "--inject-times: '0' is not a multiple in (0, 10]"},
      {inject + "11", "--inject-times: '11' is not a multiple in (0, 10]"},
      {inject + "1,,2", "--inject-times: '' is not a multiple in (0, 10]"},
      {inject + "1e0", "--inject-times: '1e0' is not a multiple in (0, 10]"},
      {inject + "'1, 2'", "--inject-times: ' 2' is not a multiple in (0, 10]"},
      {inject + "1,1.0", "--inject-times: '1.0' is given twice"},
      {inject + "2 --case 'ok + disparity_offset (1.5 × its limit)'",
       "--case: no case named 'ok + disparity_offset (1.5 × its limit)' on the --inject-into "
       "tables at the --inject-times multiples"},
      {inject + "1,", "--inject-times: '1,' is not a list of multiples in (0, 10]"},
      {" --cases --inject-times 2", "--inject-times goes with --inject-into"}};
  for (const auto& [args, message] : bad_times) {
    r = Diagnose(args, d);
    EXPECT_EQ(r.code, 2) << args << ": " << r.err;
    EXPECT_EQ(Lines(r.err), 1) << args << ": " << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << ": " << r.err;
    EXPECT_FALSE(fs::exists(d / "out")) << args;
  }
}

// Any campaign: a user's unit, one light and one preset, 16 test points of its own (not the
// article's) × emitter off and on, is diagnosed from its own cells.
TEST(DiagnoseGapInput, AUsersUnitOfOneLightAndOnePresetIsDiagnosedOnItsOwnCells) {
  const fs::path d = Dir("unit");
  sim::SimParams base = test_support::ArticleSimParams();
  base.protocol.distances_m = {3, 6, 9, 13};
  base.protocol.angles_deg = {-15, 0, 5, 25};
  gap::WithheldCase unit = gap::NullCases(1)[0];
  unit.unit = true;
  gap::SimulateOptions options;
  options.frames = 4;
  options.threads = 2;
  const auto rows = gap::MakeCaseTable(base, unit, 6000, options);
  ASSERT_EQ(rows.size(), 32u);
  io::WriteMetricsCsv((d / "unit.csv").string(), rows);
  const auto r = Diagnose("--real " + (d / "unit.csv").string() + " --out " +
                              (d / "out").string() + kFast,
                          d);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string json = ReadFile(d / "out" / "gap.json");
  EXPECT_NE(json.find("\"rows_used\": 32"), std::string::npos);
  EXPECT_NE(json.find("\"rows_skipped\": []"), std::string::npos);
  EXPECT_NE(json.find("\"scenario\": \"daylight/HA\""), std::string::npos);
  EXPECT_EQ(json.find("sunset"), std::string::npos);
  EXPECT_NE(json.find("_13m_-15deg_HA"), std::string::npos);  // its own test points
}

}  // namespace
}  // namespace depthbias
