// Hostile input to the five tools as a user runs them (tests/README.md's audit table): one line
// naming the file, exit status 2 and nothing written for input, usage and output errors, 1 when
// some rows failed; never a crash, a hang, an input or a device overwritten, a half output.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "io/bag.h"
#include "io/csv.h"
#include "io/metrics_csv.h"
#include "support/tools.h"
#include "test_dir.h"

extern char** environ;

namespace depthbias::io {
namespace {

namespace fs = std::filesystem;
using testing::FreshDir;

const std::string kSource = DEPTHBIAS_SOURCE_DIR;
const std::string kArticle = kSource + "/config/data/paper_d455_outdoor.csv";
const std::string kDemo = kSource + "/config/protocol_demo.yaml";
const std::string kFixture = kSource + "/tests/data/bags/d455_depth_1mm.bag";

using test_support::Bin;
using test_support::ReadFile;
void Put(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

bool Has(const std::string& text, const std::string& needle) {
  return text.find(needle) != std::string::npos;
}

int Lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

using AppRun = test_support::ToolRun;

// Runs a shell command line, `prefix` first in the same shell (ulimit, trap, export); what it
// wrote is removed from dir, so that dir shows only what the tool left.
AppRun Shell(const std::string& cmd, const fs::path& dir, const std::string& prefix = "") {
  const std::string line = prefix + (prefix.empty() ? "" : "; ") + "exec " + cmd;
  AppRun r = test_support::RunShell("bash -c '" + line + "'", dir);
  fs::remove(dir / "stdout.txt");
  fs::remove(dir / "stderr.txt");
  return r;
}

AppRun Exec(const std::string& app, const std::string& args, const fs::path& dir,
         const std::string& prefix = "") {
  return Shell(Bin(app) + " " + args, dir, prefix);
}

// A failed run: exit 2, one line on stderr holding `needle`.
void ExpectRefused(const AppRun& r, const std::string& needle, const std::string& what) {
  EXPECT_EQ(r.code, 2) << what << ": " << r.err;
  EXPECT_EQ(Lines(r.err), 1) << what << ": " << r.err;
  EXPECT_TRUE(Has(r.err, needle)) << what << ": " << r.err;
}

std::vector<std::string> Files(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

// A bag whose depth focal lengths are fx (BagWriter refuses to write such a camera: the bytes
// are patched after).
void ForgedBag(const fs::path& path, double fx) {
  BagWriterConfig c;
  c.intrinsics.width = 16, c.intrinsics.height = 12, c.intrinsics.ppx = 8, c.intrinsics.ppy = 6;
  c.intrinsics.fx = c.intrinsics.fy = 12.3456789;
  {
    BagWriter w(path.string(), c);
    for (int i = 0; i < 3; ++i) {
      records::DepthFrame f;
      f.width = 16, f.height = 12, f.frame_number = i, f.timestamp_ms = 33.0 * i;
      f.counts.assign(16 * 12, 4000);
      w.Write(f);
    }
    w.Close();
  }
  std::string bytes = ReadFile(path);
  const double from = 12.3456789;
  const std::string a(reinterpret_cast<const char*>(&from), 8);
  const std::string b(reinterpret_cast<const char*>(&fx), 8);
  for (size_t at = bytes.find(a); at != std::string::npos; at = bytes.find(a, at + 1))
    bytes.replace(at, 8, b);
  Put(path, bytes);
}

const std::string kHeader =
    "bag,light,emitter,preset,distance_m,angle_deg,frames,mean_m,median_m,plane_std_m,"
    "hole_rate_pct,valid_pct\n";

// ---------------------------------------------------------------- class 1

TEST(HostileApps, AbsurdIntrinsicsInOneBagFailThatRowNotTheBatch) {
  const fs::path d = FreshDir("hostile_apps");
  fs::create_directories(d / "bags");
  fs::copy_file(kFixture, d / "bags/good.bag");
  ForgedBag(d / "bags/tiny_fx.bag", 1e-300);
  ForgedBag(d / "bags/huge_fx.bag", 1e300);
  const AppRun r = Exec("panel_extract", "--jobs 2 --out " + (d / "m.csv").string() + " " +
                                          (d / "bags").string(), d);
  EXPECT_EQ(r.code, 1) << r.err;  // some rows failed
  EXPECT_FALSE(Has(r.err, "[pcl")) << r.err;  // PCL never prints
  const auto rows = ReadMetricsCsv((d / "m.csv").string());
  ASSERT_EQ(rows.size(), 3u);
  for (const auto& m : rows) {
    if (m.bag == "good.bag") {
      EXPECT_NE(m.status, "error") << m.message;
    } else {
      EXPECT_EQ(m.status, "error") << m.bag;
      EXPECT_TRUE(Has(m.message, (d / "bags" / m.bag).string())) << m.message;
      EXPECT_TRUE(Has(m.message, "focal length")) << m.message;
    }
  }
  const AppRun sim = Exec("simulate", "--protocol " + kDemo + " --metrics-only --frames 1 --out " +
                                       (d / "s.csv").string() + " --sensor-from " +
                                       (d / "bags/tiny_fx.bag").string(), d);
  ExpectRefused(sim, (d / "bags/tiny_fx.bag").string() + ": depth camera_info: focal length 1e-300",
                "simulate --sensor-from");
  EXPECT_FALSE(fs::exists(d / "s.csv"));
}

// ---------------------------------------------------------------- class 2

TEST(HostileApps, FullDiskEndsInOneLineAndNoBagNotAnAbort) {
  const fs::path d = FreshDir("hostile_apps");
  const AppRun r = Exec("simulate", "--protocol " + kDemo + " --frames 3 --threads 2 --out-dir " +
                                     (d / "bags").string(), d,
                     "trap \"\" XFSZ; ulimit -f 2000");
  ExpectRefused(r, "cannot write frame", "ulimit -f");
  EXPECT_TRUE(Has(r.err, (d / "bags").string())) << r.err;
  EXPECT_TRUE(Files(d / "bags").empty());  // no bag, no .part, no manifest
  ExpectRefused(Exec("fit_bias", "--in " + kArticle + " --out /dev/full --cv none", d),
                "/dev/full: write failed: No space left on device", "fit_bias --out /dev/full");
}

// ---------------------------------------------------------------- class 3

TEST(HostileApps, YamlBombsAreRefusedNamingTheFile) {
  const fs::path d = FreshDir("hostile_apps");
  std::string bomb = "a0: &a0 {x: 1}\n";
  for (int i = 1; i <= 9; ++i) {
    bomb += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " {";
    for (int k = 0; k < 9; ++k)
      bomb += (k ? ", k" : "k") + std::to_string(k) + ": *a" + std::to_string(i - 1);
    bomb += "}\n";
  }
  const fs::path y = d / "bomb.yaml";
  Put(y, bomb);
  const std::string says = y.string() + ": more than 100000 values once its aliases";
  const auto start = std::chrono::steady_clock::now();
  ExpectRefused(Exec("panel_extract", "--config " + y.string() + " " + kFixture, d), says,
                "panel_extract --config");
  Put(d / "m.csv", ReadFile(kArticle));
  ExpectRefused(Exec("correct_depth", "--weights " + y.string() + " --in " +
                                          (d / "m.csv").string() + " --out " +
                                          (d / "c.csv").string(), d),
                says, "correct_depth --weights");
  for (const std::string flag : {"--protocol", "--effects", "--sensor"}) {
    const std::string protocol = flag == std::string("--protocol") ? y.string() : kDemo;
    const std::string extra = flag == std::string("--protocol") ? "" : " " + flag + " " + y.string();
    ExpectRefused(Exec("simulate", "--protocol " + protocol + extra +
                                       " --metrics-only --frames 1 --out " +
                                       (d / "s.csv").string(), d),
                  says, std::string("simulate ") + flag);
  }
  ExpectRefused(Exec("panel_extract", "--config /dev/zero " + kFixture, d), "/dev/zero",
                "panel_extract --config /dev/zero");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
            60.0);  // a bound on a hang (minutes before), not a timing test
  EXPECT_EQ(Files(d), std::vector<std::string>({"bomb.yaml", "m.csv"}));
}

// ---------------------------------------------------------------- class 4

TEST(HostileApps, NoOutputLandsOnAnInputOrReplacesADevice) {
  const fs::path d = FreshDir("hostile_apps");
  const fs::path own = d / "sim_daylight_emitter-on_8m_0deg_HD.bag";  // a recording's own name
  fs::copy_file(kFixture, own);
  const std::string before = ReadFile(own);
  const AppRun r = Exec("simulate", "--protocol " + kDemo + " --frames 2 --sensor-from " +
                                     own.string() + " --out-dir " + d.string(), d);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(Has(r.err, own.string() + ": is also an input")) << r.err;
  EXPECT_EQ(ReadFile(own), before);
  EXPECT_EQ(Files(d), std::vector<std::string>({own.filename().string()}));
  // Devices are written in place (as root a rename would replace them with a file).
  const AppRun null_out = Exec("fit_bias", "--in " + kArticle + " --out /dev/null --cv none", d);
  EXPECT_EQ(null_out.code, 0) << null_out.err;
  const AppRun null_rows = Exec("panel_extract", "--out /dev/null " + kFixture, d);
  EXPECT_NE(null_rows.code, 2) << null_rows.err;
  struct stat st {};
  ASSERT_EQ(::lstat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  // A pipe nobody reads is refused, not waited on for ever, and stays a pipe.
  const fs::path fifo = d / "out.yaml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  ExpectRefused(Exec("fit_bias", "--in " + kArticle + " --cv none --out " + fifo.string(), d),
                fifo.string() + ": is a pipe that nobody reads", "fit_bias --out FIFO");
  ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  // /dev/stdout redirected to a file: the shell's file gets the table.
  const AppRun to_stdout = Exec("fit_bias", "--in " + kArticle + " --out /dev/stdout --cv none", d);
  EXPECT_EQ(to_stdout.code, 0) << to_stdout.err;
  EXPECT_TRUE(Has(to_stdout.out, "schema: depthbias.weights/2")) << to_stdout.out;
}

// ---------------------------------------------------------------- class 5

TEST(HostileApps, SimulateWritesAllOrNothing) {
  const fs::path d = FreshDir("hostile_apps");
  // Duplicate distances name two recordings alike.
  Put(d / "dup.yaml", "protocol: {distances_m: [4, 4], angles_deg: [0], presets: [HA],\n"
                      "  emitters: [\"on\"], lights: [daylight], frames: 2}\n");
  fs::create_directories(d / "out");
  ExpectRefused(Exec("simulate", "--protocol " + (d / "dup.yaml").string() + " --out-dir " +
                                     (d / "out").string(), d),
                "given for two outputs", "duplicate distances");
  EXPECT_TRUE(Files(d / "out").empty());
  // A folder has a recording's name: refused before any recording is written.
  fs::create_directories(d / "out/sim_daylight_emitter-on_16m_20deg_HD.bag");
  ExpectRefused(Exec("simulate", "--protocol " + kDemo + " --frames 2 --out-dir " +
                                     (d / "out").string(), d),
                "exists and is not a regular file", "folder named like a bag");
  EXPECT_EQ(Files(d / "out"), std::vector<std::string>({"sim_daylight_emitter-on_16m_20deg_HD.bag"}));
  // Absurd sizes are refused before any work.
  ExpectRefused(Exec("simulate", "--protocol " + kDemo + " --frames 1e9 --out-dir " +
                                     (d / "big").string(), d),
                "--frames '1e9' is not a whole number in [1, 100000]", "--frames 1e9");
  ExpectRefused(Exec("simulate", "--protocol " + kDemo + " --frames 100000 --out-dir " +
                                     (d / "big").string(), d),
                " are free there", "--frames 100000");
  EXPECT_FALSE(fs::exists(d / "big"));
}

// Starts simulate, waits for its first .part, signals it: no bag, no .part, no manifest.
TEST(HostileApps, InterruptedSimulationLeavesNothing) {
  const fs::path d = FreshDir("hostile_apps");
  for (int sig : {SIGINT, SIGTERM}) {
    const fs::path out = d / ("out" + std::to_string(sig));
    const std::string cmd = Bin("simulate") + " --protocol " + kDemo + " --frames 20000" +
                            " --threads 1 --sensor-from " + kFixture + " --out-dir " +
                            out.string() + " > /dev/null 2> " + (d / "err").string();
    pid_t pid = 0;
    const char* argv[] = {"bash", "-c", nullptr, nullptr};
    const std::string exec_cmd = "exec " + cmd;
    argv[2] = exec_cmd.c_str();
    ASSERT_EQ(::posix_spawn(&pid, "/bin/bash", nullptr, nullptr, const_cast<char**>(argv),
                            environ),
              0);
    bool started = false;
    for (int i = 0; i < 600 && !started; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      std::error_code ec;
      if (fs::is_directory(out, ec))
        for (const auto& e : fs::directory_iterator(out, ec))
          started = started || e.path().extension() == ".part";
    }
    EXPECT_TRUE(started) << ReadFile(d / "err");
    ::kill(pid, sig);
    int status = 0;
    ::waitpid(pid, &status, 0);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << status;
    EXPECT_TRUE(Files(out).empty()) << Files(out).size() << " files left";
  }
}

// ---------------------------------------------------------------- class 6

TEST(HostileApps, AbsurdNumbersAreRefusedNotPassedOn) {
  const fs::path d = FreshDir("hostile_apps");
  const fs::path w = d / "w.yaml";
  ASSERT_EQ(Exec("fit_bias", "--in " + kArticle + " --out " + w.string() + " --model paper6", d)
                .code, 0);
  const std::string ok_row = "x,daylight,on,HA,4,0,30,4,4.05,0.05,1,99\n";
  struct Case {
    std::string row, says;
  };
  for (const Case& c : std::vector<Case>{
           {"x,daylight,on,HA,4,90,30,4,4.05,0.05,1,99\n", "m.csv:2: column 'angle_deg': 90"},
           {"x,daylight,on,HA,4,0,30,4,0,0.05,1,99\n", "column 'median_m': 0 is outside"},
           {"x,daylight,on,HA,4,0,30,4,-5,0.05,1,99\n", "column 'median_m': -5 is outside"},
           {"x,daylight,on,HA,0,0,30,4,4,0.05,1,99\n", "column 'distance_m': 0 is outside"}}) {
    Put(d / "m.csv", kHeader + c.row);
    ExpectRefused(Exec("correct_depth", "--weights " + w.string() + " --in " +
                                            (d / "m.csv").string() + " --out " +
                                            (d / "c.csv").string(), d),
                  c.says, "correct_depth " + c.row);
    ExpectRefused(Exec("fit_bias", "--in " + (d / "m.csv").string() + " --out " +
                                       (d / "w2.yaml").string(), d),
                  c.says, "fit_bias " + c.row);
  }
  EXPECT_FALSE(fs::exists(d / "c.csv"));
  // Negative nominal distances in a whole table: refused, never fitted.
  std::string table = kHeader;
  for (const char* dist : {"-4", "-8", "-12", "-16"})
    for (const char* a : {"0", "10", "20", "35"})
      table += std::string("r") + dist + a + ",daylight,on,HA," + dist + "," + a +
               ",30,4,4.05,0.05,1,99\n";
  Put(d / "neg.csv", table);
  ExpectRefused(Exec("fit_bias", "--in " + (d / "neg.csv").string() + " --out " +
                                     (d / "w2.yaml").string(), d),
                "column 'distance_m': -4 is outside (0, 1000] m", "negative distances");
  // Weights whose margin would shrink: a negative variance, an indefinite covariance.
  Put(d / "m.csv", kHeader + ok_row);
  std::string weights = ReadFile(w);
  const size_t cov = weights.find("covariance:");
  ASSERT_NE(cov, std::string::npos);
  const size_t first = weights.find("[", cov) + 1;
  std::string negative = weights;
  negative.replace(first, weights.find(",", first) - first, "-0.2");
  Put(d / "neg.yaml", negative);
  ExpectRefused(Exec("correct_depth", "--weights " + (d / "neg.yaml").string() + " --in " +
                                          (d / "m.csv").string() + " --out " +
                                          (d / "c.csv").string(), d),
                "-0.2 is a negative variance", "negative covariance");
  // Unknown scatter (.nan, a group fitted with n <= p): the margin is left empty, not made
  // as narrow as the parameter uncertainty alone.
  std::string unknown = weights;
  for (size_t at = unknown.find("residual_std_m: "); at != std::string::npos;
       at = unknown.find("residual_std_m: ", at + 1))
    unknown.replace(at + 16, unknown.find('\n', at) - at - 16, ".nan");
  // ... and no fitted residual model (schema 2's margin:), which would otherwise stand in.
  for (size_t at = unknown.find("    margin: {"); at != std::string::npos;
       at = unknown.find("    margin: {", at))
    unknown.erase(at, unknown.find('\n', at) - at + 1);
  Put(d / "nan.yaml", unknown);
  const AppRun nan_run = Exec("correct_depth", "--weights " + (d / "nan.yaml").string() + " --in " +
                                                (d / "m.csv").string() + " --out " +
                                                (d / "c.csv").string(), d);
  ASSERT_EQ(nan_run.code, 0) << nan_run.err;
  const CsvTable t = ReadCsv((d / "c.csv").string());
  EXPECT_FALSE(std::isnan(t.Number(0, t.RequireColumn("corrected_m"))));
  EXPECT_TRUE(std::isnan(t.Number(0, t.RequireColumn("margin_m"))));
  EXPECT_TRUE(std::isnan(t.Number(0, t.RequireColumn("predictive_std_m"))));
}

// ---------------------------------------------------------------- class 7

TEST(HostileApps, NoNoiseAndNoSilence) {
  const fs::path d = FreshDir("hostile_apps");
  // rospack's warnings when HOME cannot be written (another user, HOME missing).
  // Only where that user can reach the tool and the fixture: a checkout in a private folder
  // (mktemp -d: 0700) keeps it out of the whole tree.
  const std::string as_other = "setpriv --reuid=65534 --regid=65534 --clear-groups ";
  if (::geteuid() == 0 && ::access("/usr/bin/setpriv", X_OK) == 0 &&
      Shell(as_other + "test -x " + Bin("bag_info") + " -a -r " + kFixture, d).code == 0) {
    const AppRun r = Shell(as_other + Bin("bag_info") + " " + kFixture, d,
                           "export HOME=/nonexistent; unset ROS_HOME");
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err, "");
  }
  // A folder with what a scan cannot read: each gets a row, none is skipped silently.
  fs::create_directories(d / "bags");
  fs::copy_file(kFixture, d / "bags/good.bag");
  fs::create_symlink("gone.bag", d / "bags/dangling.bag");
  fs::create_symlink("loop.bag", d / "bags/loop.bag");
  ASSERT_EQ(::mkfifo((d / "bags/fifo.bag").c_str(), 0600), 0);
  const AppRun r = Exec("panel_extract", "--out " + (d / "m.csv").string() + " " +
                                          (d / "bags").string(), d);
  EXPECT_EQ(r.code, 1) << r.err;
  std::map<std::string, std::string> status;
  for (const auto& m : ReadMetricsCsv((d / "m.csv").string())) status[m.bag] = m.message;
  EXPECT_EQ(status.size(), 4u);
  EXPECT_TRUE(Has(status["dangling.bag"], "leads nowhere")) << status["dangling.bag"];
  EXPECT_TRUE(Has(status["loop.bag"], "loop")) << status["loop.bag"];
  EXPECT_TRUE(Has(status["fifo.bag"], "a pipe")) << status["fifo.bag"];
  EXPECT_TRUE(Has(r.err, "4 recordings: ")) << r.err;
  // A fit that fails says so in one line, with no Ceres or glog lines before it.
  Put(d / "one.csv", kHeader + "x,daylight,on,HA,4,0,30,4,4.05,0.05,1,99\n");
  ExpectRefused(Exec("fit_bias", "--in " + (d / "one.csv").string() + " --out " +
                                     (d / "w.yaml").string(), d),
                (d / "one.csv").string() + ": ", "fit_bias on one row");
}

// ---------------------------------------------------------------- class 8

TEST(HostileApps, HelpExitCodesSummariesAndEarlyOutputChecks) {
  const fs::path d = FreshDir("hostile_apps");
  const std::map<std::string, std::vector<std::string>> options = {
      {"bag_info", {"--json", "--partial", "--read-all"}},
      {"panel_extract",
       {"--manifest", "--config", "--out", "--panels-out", "--jobs", "--region-mode", "--boxes",
        "--quiet"}},
      {"fit_bias",
       {"--in", "--out", "--model", "--lambda", "--loss", "--loss-scale", "--group-by", "--cv",
        "--weight-valid", "--focal-px", "--baseline-m", "--prior", "--nested", "--cv-out"}},
      {"correct_depth", {"--weights", "--in", "--out", "--k"}},
      {"simulate",
       {"--protocol", "--out-dir", "--metrics-only", "--calibrate-to", "--out", "--frames",
        "--seed", "--effects", "--sensor", "--sensor-from", "--margin-px", "--threads"}},
  };
  for (const auto& [app, flags] : options) {
    const AppRun help = Exec(app, "--help", d);
    EXPECT_EQ(help.code, 0) << app;
    for (const auto& f : flags) EXPECT_TRUE(Has(help.out, "  " + f + " ")) << app << " " << f;
    EXPECT_TRUE(Has(help.out, "Exit status: 0")) << app;
    const AppRun usage = Exec(app, "--no-such-flag", d);
    EXPECT_EQ(usage.code, 2) << app << ": " << usage.err;  // the same code in every tool
    EXPECT_EQ(Lines(usage.err), 1) << app << ": " << usage.err;
  }
  // An output that cannot be written is found before the work.
  const auto start = std::chrono::steady_clock::now();
  ExpectRefused(Exec("panel_extract", "--out " + (d / "no/such/m.csv").string() + " " + kFixture,
                     d),
                "does not exist", "panel_extract --out in a missing folder");
  ExpectRefused(Exec("fit_bias", "--in " + kArticle + " --out " + d.string(), d), "is a folder",
                "fit_bias --out a folder");
  Put(d / "file", "x");
  ExpectRefused(Exec("simulate", "--protocol " + kDemo + " --out-dir " + (d / "file/bags").string(),
                     d),
                "is not a folder", "simulate --out-dir under a file");
  ExpectRefused(Exec("simulate", "--protocol " + kDemo + " --metrics-only --out " +
                                     (d / "no/m.csv").string(), d),
                "does not exist", "simulate --out in a missing folder");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
            60.0);
  // Rows failed: 1, with the summary line; no progress control characters off a terminal.
  const AppRun rows = Exec("panel_extract", "--out " + (d / "m.csv").string() + " " + kFixture, d);
  EXPECT_EQ(rows.code, 1) << rows.err;
  EXPECT_TRUE(Has(rows.err, "panel_extract: 1 recording: 1 no_panel \u2192 " +
                                (d / "m.csv").string()))
      << rows.err;
  EXPECT_FALSE(Has(rows.err, "\r")) << rows.err;
  const AppRun bags = Exec("bag_info", kFixture + " " + (d / "file").string(), d);
  EXPECT_EQ(bags.code, 1) << bags.err;
  EXPECT_TRUE(Has(bags.err, "2 bags: 1 ok, 1 unreadable")) << bags.err;
  // Progress on a terminal (script(1) gives the tool one).
  if (::access("/usr/bin/script", X_OK) == 0) {
    const AppRun tty = Shell("script -qec \"" + Bin("simulate") + " --protocol " + kDemo +
                              " --frames 1 --sensor-from " + kFixture + " --out-dir " +
                              (d / "tty").string() + "\" /dev/null",
                          d);
    EXPECT_EQ(tty.code, 0) << tty.err;
    EXPECT_TRUE(Has(tty.out, "[8/8] ")) << tty.out;
  }
}

}  // namespace
}  // namespace depthbias::io
