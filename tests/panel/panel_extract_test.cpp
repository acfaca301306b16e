// panel_extract on recordings written by librealsense's recorder with known truth
// (scripts/make_panel_bags.py, run by the panel_fixture_bags test), and on malformed inputs.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "io/atomic_file.h"
#include "io/csv.h"
#include "io/metrics_csv.h"

namespace fs = std::filesystem;

namespace depthbias {
namespace {

const std::string kBags = DEPTHBIAS_PANEL_BAGS;

struct AppRun {
  int code = -1;
  std::string err;
};

std::string Bin() {
  const char* b = std::getenv("DEPTHBIAS_BIN");
  return b ? b : DEPTHBIAS_BINARY_DIR "/apps";
}

// A fresh folder for one test's outputs.
fs::path Dir(const std::string& name) {
  const fs::path d = fs::path(DEPTHBIAS_BINARY_DIR) / "panel_extract_test" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

AppRun Extract(const std::string& args, const fs::path& dir) {
  const fs::path err = dir / "stderr.txt";
  const std::string cmd = Bin() + "/panel_extract " + args + " 2> " + err.string();
  const int status = std::system(cmd.c_str());
  AppRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err);
  std::stringstream ss;
  ss << in.rdbuf();
  r.err = ss.str();
  return r;
}

YAML::Node Truth(const std::string& bag) {
  const fs::path p = fs::path(kBags) / (fs::path(bag).stem().string() + ".truth.json");
  return YAML::LoadFile(p.string());  // throws (and fails the test) if the fixture is missing
}

// Pixel set of [v, u0, u1) runs.
std::set<long> Pixels(const YAML::Node& runs) {
  std::set<long> s;
  for (const auto& r : runs)
    for (long u = r[1].as<long>(); u < r[2].as<long>(); ++u) s.insert(r[0].as<long>() * 4096 + u);
  return s;
}

double IoU(const std::set<long>& a, const std::set<long>& b) {
  std::size_t inter = 0;
  for (long x : a) inter += b.count(x);
  const std::size_t uni = a.size() + b.size() - inter;
  return uni ? static_cast<double>(inter) / uni : 0.0;
}

// ΔZ of one 1/32 px disparity step at depth Z: Z²/(32·f·B).
double QuantStep(const YAML::Node& t, double z) {
  return z * z / (32.0 * t["fx"].as<double>() * t["baseline_m"].as<double>());
}

struct Errors {
  double median_m, tol_m, iou, hole_pts, azimuth_deg, tilt_deg;
};

// Compares one metrics row (and its panels.json entry) with the truth.
Errors Compare(const records::PanelMetrics& m, const YAML::Node& panel, const YAML::Node& t) {
  const double z = t["true_median_depth_m"].as<double>();
  Errors e;
  e.median_m = m.median_m - z;
  e.tol_m = QuantStep(t, z) + 0.001 * z;
  e.iou = IoU(Pixels(panel["region_runs"]), Pixels(t["footprint_runs"]));
  e.hole_pts = m.hole_rate_pct - t["true_hole_rate_pct"].as<double>();
  e.azimuth_deg = m.azimuth_deg - t["azimuth_deg"].as<double>();
  e.tilt_deg = m.normal_tilt_deg - t["normal_tilt_deg"].as<double>();
  return e;
}

void ExpectWithin(const Errors& e, const std::string& bag, bool check_iou) {
  SCOPED_TRACE(bag);
  EXPECT_LE(std::fabs(e.median_m), e.tol_m);
  if (check_iou) {
    EXPECT_GE(e.iou, 0.85);
  }
  EXPECT_LE(std::fabs(e.hole_pts), 1.0);
  EXPECT_LE(std::fabs(e.azimuth_deg), 0.5);
  EXPECT_LE(std::fabs(e.tilt_deg), 2.0);
}

std::map<std::string, YAML::Node> PanelsByBag(const fs::path& json) {
  std::map<std::string, YAML::Node> out;
  const YAML::Node root = YAML::LoadFile(json.string());
  for (std::size_t k = 0; k < root.size(); ++k) out[root[k]["bag"].as<std::string>()] = root[k];
  return out;
}

TEST(PanelExtract, MeasuresEveryTestPointWithinTolerance) {
  const fs::path d = Dir("grid");
  const std::string common = "--manifest " + kBags + "/manifest.csv --jobs 2 ";
  const AppRun a = Extract(common + "--out " + (d / "auto.csv").string() + " --panels-out " +
                            (d / "auto.json").string() + " " + kBags, d);
  ASSERT_EQ(a.code, 0) << a.err;
  const AppRun b = Extract(common + "--region-mode box --boxes " + kBags + "/boxes.json --out " +
                            (d / "box.csv").string() + " --panels-out " +
                            (d / "box.json").string() + " " + kBags, d);
  ASSERT_EQ(b.code, 0) << b.err;
  const auto rows = io::ReadMetricsCsv((d / "auto.csv").string());
  const auto box_rows = io::ReadMetricsCsv((d / "box.csv").string());
  auto panels = PanelsByBag(d / "auto.json");
  auto box_panels = PanelsByBag(d / "box.json");
  ASSERT_EQ(rows.size(), box_rows.size());
  int grid = 0;
  std::printf("%-22s %9s %8s %6s %7s %7s %7s | box: %9s %7s %7s %7s\n", "recording",
              "median_err", "tol", "IoU", "hole", "azim", "tilt", "median_err", "hole", "azim",
              "tilt");
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const records::PanelMetrics& m = rows[k];
    ASSERT_EQ(m.status, "ok") << m.bag << ": " << m.message;
    ASSERT_EQ(box_rows[k].bag, m.bag);
    ASSERT_EQ(box_rows[k].status, "ok") << m.bag << ": " << box_rows[k].message;
    const YAML::Node t = Truth(m.bag);
    EXPECT_EQ(m.preset, t["preset"].as<std::string>());
    EXPECT_EQ(m.emitter, t["emitter"].as<std::string>());
    EXPECT_EQ(m.distance_m, t["distance_m"].as<double>());
    const Errors e = Compare(m, panels[m.bag], t);
    const Errors eb = Compare(box_rows[k], box_panels[m.bag], t);
    std::printf("%-22s %+9.4f %8.4f %6.3f %+7.2f %+7.3f %+7.2f | box: %+9.4f %+7.2f %+7.3f %+7.2f\n",
                m.bag.c_str(), e.median_m, e.tol_m, e.iou, e.hole_pts, e.azimuth_deg, e.tilt_deg,
                eb.median_m, eb.hole_pts, eb.azimuth_deg, eb.tilt_deg);
    ExpectWithin(e, m.bag, true);
    // The manual box lies inside the panel: the same tolerances, and the two methods agree.
    ExpectWithin(eb, m.bag + " (box)", false);
    EXPECT_LE(std::fabs(m.median_m - box_rows[k].median_m), e.tol_m) << m.bag;
    EXPECT_LE(std::fabs(m.hole_rate_pct - box_rows[k].hole_rate_pct), 1.0) << m.bag;
    EXPECT_LE(std::fabs(m.normal_tilt_deg - box_rows[k].normal_tilt_deg), 2.0) << m.bag;
    grid += !t["clutter"].as<bool>();
  }
  EXPECT_EQ(grid, 16);  // the article's 16 test points, plus the cluttered scenes
}

TEST(PanelExtract, ClutteredSceneStillSelectsThePanel) {
  const fs::path d = Dir("clutter");
  // Without the manifest's search window: the panel must win on size, shape and facing alone.
  std::ofstream(d / "c.yaml") << "use_search_window: false\n";
  const AppRun r = Extract("--manifest " + kBags + "/manifest.csv --config " +
                               (d / "c.yaml").string() + " --out " + (d / "m.csv").string() + " --panels-out " +
                            (d / "p.json").string() + " " + kBags + "/clutter_08m_20deg.bag " +
                            kBags + "/clutter_12m_00deg.bag", d);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = io::ReadMetricsCsv((d / "m.csv").string());
  auto panels = PanelsByBag(d / "p.json");
  ASSERT_EQ(rows.size(), 2u);
  for (const auto& m : rows) {
    const YAML::Node t = Truth(m.bag);
    ASSERT_TRUE(t["clutter"].as<bool>());
    EXPECT_GE(panels[m.bag]["candidates"].size(), 3u) << "the clutter must be seen";
    ExpectWithin(Compare(m, panels[m.bag], t), m.bag, true);
  }
}

// Malformed inputs: one clear line naming the file, no crash, nothing half-written.
class PanelExtractBadInput : public ::testing::Test {
 protected:
  void SetUp() override { d_ = Dir(::testing::UnitTest::GetInstance()->current_test_info()->name()); }
  std::string Out() const { return (d_ / "m.csv").string(); }
  bool NothingWritten() const {
    for (const auto& e : fs::directory_iterator(d_))
      if (e.path().filename() != "stderr.txt") return false;
    return true;
  }
  fs::path d_;
};

TEST_F(PanelExtractBadInput, BadRecordingsGetErrorRowsAndTheBatchGoesOn) {
  const std::string good = kBags + "/panel_04m_00deg.bag";
  const fs::path text = d_ / "notes.bag", empty = d_ / "empty.bag", cut = d_ / "cut.bag";
  std::ofstream(text) << "not a bag\n";
  std::ofstream(empty).close();
  fs::copy_file(good, cut);
  fs::resize_file(cut, fs::file_size(cut) / 2);
  std::ofstream(d_ / "manifest.csv") << "bag,distance_m,angle_deg,light\n"
                                     << "notes.bag,4,0,x\nempty.bag,4,0,x\ncut.bag,4,0,x\n"
                                     << "missing.bag,4,0,x\n" << good << ",4,0,x\n";
  const AppRun r = Extract("--manifest " + (d_ / "manifest.csv").string() + " --out " + Out() +
                               " " + text.string() + " " + empty.string() + " " +
                            cut.string() + " " + (d_ / "missing.bag").string() + " " + good, d_);
  EXPECT_EQ(r.code, 1) << r.err;
  const auto rows = io::ReadMetricsCsv(Out());
  ASSERT_EQ(rows.size(), 5u);
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(rows[k].status, "error") << rows[k].bag;
    EXPECT_NE(rows[k].message.find(rows[k].bag), std::string::npos) << rows[k].message;
    EXPECT_EQ(rows[k].message.find('\n'), std::string::npos);
  }
  EXPECT_EQ(rows[4].status, "ok") << rows[4].message;
}

TEST_F(PanelExtractBadInput, EmptyDirectoryIsRefused) {
  fs::create_directories(d_ / "nothing");
  const AppRun r = Extract("--out " + Out() + " " + (d_ / "nothing").string(), d_);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("nothing: no .bag file"), std::string::npos) << r.err;
  fs::remove(d_ / "nothing");
  EXPECT_TRUE(NothingWritten());
}

TEST_F(PanelExtractBadInput, ManifestWithoutTheBagsRowGivesAnErrorRow) {
  std::ofstream(d_ / "manifest.csv") << "bag,distance_m,angle_deg,light\nother.bag,4,0,daylight\n";
  const AppRun r = Extract("--manifest " + (d_ / "manifest.csv").string() + " --out " + Out() +
                            " " + kBags + "/panel_04m_00deg.bag", d_);
  EXPECT_EQ(r.code, 1);
  // Without its manifest row the distance is unknown, so the row is read as plain CSV.
  const io::CsvTable t = io::ReadCsv(Out());
  ASSERT_EQ(t.rows.size(), 1u);
  EXPECT_EQ(t.Cell(0, t.RequireColumn("status")), "error");
  const std::string msg = t.Cell(0, t.RequireColumn("message"));
  EXPECT_NE(msg.find("panel_04m_00deg.bag: not listed in"), std::string::npos) << msg;
}

TEST_F(PanelExtractBadInput, ManifestWithBadNumbersIsRefused) {
  std::ofstream(d_ / "manifest.csv")
      << "bag,distance_m,angle_deg,light\npanel_04m_00deg.bag,four,0,daylight\n";
  const AppRun r = Extract("--manifest " + (d_ / "manifest.csv").string() + " --out " + Out() +
                            " " + kBags + "/panel_04m_00deg.bag", d_);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("manifest.csv"), std::string::npos) << r.err;
  fs::remove(d_ / "manifest.csv");
  EXPECT_TRUE(NothingWritten());
}

TEST_F(PanelExtractBadInput, BadConfigAndBoxesAreRefused) {
  std::ofstream(d_ / "c.yaml") << "panel_width_m: 1.0\nground_distance: 0.1\n";
  AppRun r = Extract("--config " + (d_ / "c.yaml").string() + " --out " + Out() + " " + kBags, d_);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("c.yaml:2: unknown parameter 'ground_distance'"), std::string::npos)
      << r.err;
  std::ofstream(d_ / "b.json") << "{\"panel_04m_00deg.bag\": [1, 2, 3]}";
  r = Extract("--region-mode box --boxes " + (d_ / "b.json").string() + " --out " + Out() +
                  " " + kBags, d_);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("b.json"), std::string::npos) << r.err;
  fs::remove(d_ / "c.yaml");
  fs::remove(d_ / "b.json");
  EXPECT_TRUE(NothingWritten());
}

TEST_F(PanelExtractBadInput, UnwritableOutputLeavesNothing) {
  const std::string bag = kBags + "/panel_04m_00deg.bag";
  AppRun r = Extract("--out " + (d_ / "no" / "m.csv").string() + " " + bag, d_);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("m.csv"), std::string::npos) << r.err;
  EXPECT_TRUE(NothingWritten());
  // The metrics are not written when panels.json cannot be: both or neither.
  r = Extract("--out " + Out() + " --panels-out " + (d_ / "no" / "p.json").string() + " " + bag,
              d_);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("p.json"), std::string::npos) << r.err;
  EXPECT_TRUE(NothingWritten());
}

// An output that is also an input (the manifest, a recording) is refused before anything runs.
TEST_F(PanelExtractBadInput, OutputsNeverOverwriteInputs) {
  const std::string bag = kBags + "/panel_04m_00deg.bag";
  const std::string manifest_text = "bag,distance_m,angle_deg,light\npanel_04m_00deg.bag,4,0,x\n";
  std::ofstream(d_ / "manifest.csv") << manifest_text;
  const std::string manifest = (d_ / "manifest.csv").string();
  AppRun r = Extract("--manifest " + manifest + " --out " + manifest + " " + bag, d_);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("is also an input"), std::string::npos) << r.err;
  EXPECT_EQ(io::ReadFile(manifest), manifest_text);
  fs::copy_file(bag, d_ / "copy.bag");
  const auto size = fs::file_size(d_ / "copy.bag");
  r = Extract("--out " + (d_ / "copy.bag").string() + " " + (d_ / "copy.bag").string(), d_);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(fs::file_size(d_ / "copy.bag"), size);
  r = Extract("--out " + Out() + " --panels-out " + Out() + " " + bag, d_);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("given for two outputs"), std::string::npos) << r.err;
  fs::remove(d_ / "copy.bag");
  fs::remove(d_ / "manifest.csv");
  EXPECT_TRUE(NothingWritten());
}

TEST_F(PanelExtractBadInput, BadFlagsGiveOneLine) {
  const std::string bag = kBags + "/panel_04m_00deg.bag";
  for (const std::string jobs : {"0", "abc", "-1", "99999999999", "2x"}) {
    const AppRun r = Extract("--jobs " + jobs + " --out " + Out() + " " + bag, d_);
    EXPECT_EQ(r.code, 2) << jobs;
    EXPECT_NE(r.err.find("--jobs '" + jobs + "'"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
  }
  const AppRun r = Extract("--out " + Out(), d_);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "panel_extract: no recording given (see panel_extract --help)\n");
  std::ofstream(d_ / "empty.yaml").close();
  const AppRun e = Extract("--config " + (d_ / "empty.yaml").string() + " --out " + Out() +
                               " " + bag, d_);
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.err.find("empty.yaml: is empty"), std::string::npos) << e.err;
  fs::remove(d_ / "empty.yaml");
  EXPECT_TRUE(NothingWritten());
}

}  // namespace
}  // namespace depthbias
