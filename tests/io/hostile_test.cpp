// Hostile input at the library level (tests/README.md's audit table, classes 1-7): implausible
// intrinsics and depth units in bags, a full disk under the bag writer, YAML bombs, outputs
// that are devices, pipes or links, all-or-none outputs and signals, absurd numbers in every
// reader, directory scans that meet what they cannot read.
#include <fcntl.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "camera/intrinsics.h"
#include "io/atomic_file.h"
#include "io/bag.h"
#include "io/bag_list.h"
#include "io/config_file.h"
#include "io/manifest.h"
#include "io/metrics_csv.h"
#include "io/ranges.h"
#include "io/temp_files.h"
#include "io/weights_yaml.h"
#include "io/yaml_limits.h"
#include "records/number_text.h"
#include "test_dir.h"

namespace depthbias::io {
namespace {

namespace fs = std::filesystem;
using testing::FreshDir;

std::string Slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void Put(const fs::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
}

bool Has(const std::string& text, const std::string& needle) {
  return text.find(needle) != std::string::npos;
}

// Runs body in a child process; returns its wait status (the parent's state stays untouched:
// rlimits, signal handlers, a changed user).
int InChild(const std::function<int()>& body) {
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(body());
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

// ---------------------------------------------------------------- class 1: intrinsics

camera::Intrinsics Good() { return camera::D455::DepthIntrinsics(); }

TEST(HostileIntrinsics, ImplausibleCamerasAreRefusedWithReadableNumbers) {
  std::string why;
  ASSERT_TRUE(Good().IsValid(&why)) << why;
  struct Case {
    std::function<void(camera::Intrinsics*)> change;
    std::string says;
  };
  const std::vector<Case> cases = {
      {[](camera::Intrinsics* in) { in->fx = in->fy = 1e-300; }, "1e-300"},
      {[](camera::Intrinsics* in) { in->fx = in->fy = 1e-100; }, "implausible"},
      {[](camera::Intrinsics* in) { in->fx = in->fy = 1e300; }, "implausible"},
      {[](camera::Intrinsics* in) { in->fx = NAN; }, "positive and finite"},
      {[](camera::Intrinsics* in) { in->fy = INFINITY; }, "positive and finite"},
      {[](camera::Intrinsics* in) { in->fx = 0; }, "positive and finite"},
      {[](camera::Intrinsics* in) { in->fy = -640; }, "positive and finite"},
      {[](camera::Intrinsics* in) { in->fx = 6400; }, "differ more than 4 times"},
      {[](camera::Intrinsics* in) { in->ppx = NAN; }, "principal point"},
      {[](camera::Intrinsics* in) { in->ppy = 1e9; }, "principal point"},
      {[](camera::Intrinsics* in) { in->width = 0; }, "image size"},
      {[](camera::Intrinsics* in) { in->height = -720; }, "image size"},
      {[](camera::Intrinsics* in) { in->width = 70000; }, "image size"},
      {[](camera::Intrinsics* in) { in->coeffs[0] = NAN; }, "distortion"},
      {[](camera::Intrinsics* in) { in->coeffs[4] = 1e6; }, "distortion"},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    camera::Intrinsics in = Good();
    cases[i].change(&in);
    why.clear();
    EXPECT_FALSE(in.IsValid(&why)) << "case " << i;
    EXPECT_TRUE(Has(why, cases[i].says)) << "case " << i << ": " << why;
    EXPECT_FALSE(Has(why, "000000")) << why;  // readable numbers, never 1e-300 as 0.000000
  }
  // Real cameras stay valid: a quarter-size sensor, a tiny fixture, a long lens.
  camera::Intrinsics small = Good();
  small.width = 320, small.height = 180, small.fx = small.fy = 160, small.ppx = 160, small.ppy = 90;
  EXPECT_TRUE(small.IsValid(&why)) << why;
  camera::Intrinsics tiny = Good();
  tiny.width = 8, tiny.height = 6, tiny.fx = 4.8, tiny.fy = 4.9, tiny.ppx = 4.3, tiny.ppy = 2.8;
  EXPECT_TRUE(tiny.IsValid(&why)) << why;
}

// A valid bag with recognisable values, then patched bytes: the reader meets what a damaged or
// forged recording holds, which BagWriter itself refuses to write.
BagWriterConfig MarkedConfig() {
  BagWriterConfig c;
  c.intrinsics.width = 16;
  c.intrinsics.height = 12;
  c.intrinsics.fx = 12.3456789;  // marker doubles, found and replaced in the file
  c.intrinsics.fy = 12.4567891;
  c.intrinsics.ppx = 8;
  c.intrinsics.ppy = 6;
  c.depth_units_m = 0.00234;  // marker float of the Depth_Units option
  c.options = {{"Visual_Preset", 3}};
  return c;
}

void WriteMarkedBag(const fs::path& path, float frame_units = 0.00123f) {
  BagWriter w(path.string(), MarkedConfig());
  for (int i = 0; i < 3; ++i) {
    records::DepthFrame f;
    f.width = 16;
    f.height = 12;
    f.depth_units_m = frame_units;
    f.frame_number = i;
    f.timestamp_ms = 100 + 33 * i;
    f.counts.assign(16 * 12, static_cast<std::uint16_t>(3000 + i));
    w.Write(f);
  }
  w.Close();
}

template <typename T>
int Patch(const fs::path& path, T from, T to) {
  std::string bytes = Slurp(path);
  const std::string a(reinterpret_cast<const char*>(&from), sizeof(T));
  const std::string b(reinterpret_cast<const char*>(&to), sizeof(T));
  int n = 0;
  for (size_t at = bytes.find(a); at != std::string::npos; at = bytes.find(a, at + 1), ++n)
    bytes.replace(at, sizeof(T), b);
  Put(path, bytes);
  return n;
}

std::string ReadError(const fs::path& path) {
  try {
    BagReader r(path.string());
    records::DepthFrame f;
    while (r.Next(&f)) {
    }
  } catch (const BagError& e) {
    return e.what();
  }
  return "";
}

TEST(HostileBags, ImplausibleIntrinsicsInABagAreRefusedNamingTheFile) {
  const fs::path d = FreshDir("hostile");
  for (double fx : {1e-300, 1e-100, 1e300, -5.0, 0.0}) {
    const fs::path bag = d / "bad_fx.bag";
    WriteMarkedBag(bag);
    ASSERT_GE(Patch(bag, 12.3456789, fx), 1);
    ASSERT_GE(Patch(bag, 12.4567891, fx), 1);
    const std::string err = ReadError(bag);
    EXPECT_TRUE(Has(err, bag.string())) << err;
    EXPECT_TRUE(Has(err, "camera_info")) << err;
    EXPECT_TRUE(Has(err, "focal length")) << err;
  }
  const fs::path nan_bag = d / "nan_ppx.bag";
  WriteMarkedBag(nan_bag);
  ASSERT_GE(Patch(nan_bag, 12.3456789, static_cast<double>(NAN)), 1);
  EXPECT_TRUE(Has(ReadError(nan_bag), "focal lengths")) << ReadError(nan_bag);
}

TEST(HostileBags, DepthUnitsZeroNegativeOrNaNAreRefusedNotReadAsOneMillimetre) {
  const fs::path d = FreshDir("hostile");
  const fs::path good = d / "good.bag";
  WriteMarkedBag(good);
  EXPECT_EQ(ReadError(good), "");
  for (float units : {0.0f, -0.001f, NAN, INFINITY, 5.0f}) {
    const fs::path frame_bag = d / "frame_units.bag";
    WriteMarkedBag(frame_bag);
    ASSERT_EQ(Patch(frame_bag, 0.00123f, units), 3);  // every frame's units
    const std::string err = ReadError(frame_bag);
    EXPECT_TRUE(Has(err, "depth units")) << units << ": " << err;
    EXPECT_TRUE(Has(err, frame_bag.string())) << err;
    const fs::path option_bag = d / "option_units.bag";
    WriteMarkedBag(option_bag);
    ASSERT_EQ(Patch(option_bag, 0.00234f, units), 1);  // the Depth_Units option
    EXPECT_TRUE(Has(ReadError(option_bag), "Depth_Units")) << ReadError(option_bag);
  }
}

TEST(HostileBags, CameraInfoOfAnotherSizeThanTheFramesIsRefused) {
  const fs::path d = FreshDir("hostile");
  const fs::path bag = d / "size.bag";
  WriteMarkedBag(bag);
  // camera_info's height and width (uint32 12, 16) come right before its distortion model's
  // name; the frames keep 16 x 12.
  std::string bytes = Slurp(bag);
  const std::uint32_t hw[3] = {12, 16, 13}, other[3] = {24, 32, 13};
  const std::string a = std::string(reinterpret_cast<const char*>(hw), 12) + "Brown Conrady";
  const size_t at = bytes.find(a);
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at, 12, std::string(reinterpret_cast<const char*>(other), 12));
  Put(bag, bytes);
  const std::string err = ReadError(bag);
  EXPECT_TRUE(Has(err, "32 x 24 px")) << err;
}

// ---------------------------------------------------------------- class 2: full disk

records::DepthFrame BigFrame(int i) {
  records::DepthFrame f;
  f.width = 1280;
  f.height = 720;
  f.frame_number = i;
  f.timestamp_ms = 33.3 * i;
  f.counts.assign(1280 * 720, static_cast<std::uint16_t>(1000 + i));
  return f;
}

// Writes frames until the writer throws; 0 when it threw a BagError and left no file.
int WriteUntilFull(const fs::path& path) {
  try {
    BagWriter w(path.string(), BagWriterConfig{});
    for (int i = 0; i < 50; ++i) w.Write(BigFrame(i));
    w.Close();
    return 3;  // the disk never filled
  } catch (const BagError& e) {
    if (e.kind() != BagError::Kind::kWrite) return 4;
  } catch (...) {
    return 5;
  }
  return fs::exists(path) || fs::exists(path.string() + ".part") ? 6 : 0;
}

TEST(HostileDisk, FileSizeLimitIsABagErrorNotAnAbort) {
  const fs::path d = FreshDir("hostile");
  const int status = InChild([&] {
    ::signal(SIGXFSZ, SIG_IGN);  // writes past the limit fail with EFBIG instead
    const rlimit lim{3u << 20, 3u << 20};
    ::setrlimit(RLIMIT_FSIZE, &lim);
    return WriteUntilFull(d / "limited.bag");
  });
  ASSERT_TRUE(WIFEXITED(status)) << "died by signal " << WTERMSIG(status);  // 6 = abort
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

TEST(HostileDisk, FullFileSystemIsABagErrorNotAnAbort) {
  const fs::path d = FreshDir("hostile") / "tmpfs";
  fs::create_directories(d);
  if (::mount("tmpfs", d.c_str(), "tmpfs", 0, "size=2m") != 0)
    GTEST_SKIP() << "cannot mount a small tmpfs here (" << std::strerror(errno) << ")";
  const int status = InChild([&] { return WriteUntilFull(d / "full.bag"); });
  const bool empty = fs::is_empty(d);
  ::umount(d.c_str());
  ASSERT_TRUE(WIFEXITED(status)) << "died by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_TRUE(empty);
}

TEST(HostileDisk, DevFullAsAnOutputIsAWriteError) {
  try {
    WriteFileAtomic("/dev/full", "a,b\n1,2\n");
    FAIL() << "no error";
  } catch (const IoError& e) {
    EXPECT_TRUE(Has(e.what(), "/dev/full: write failed: No space left on device")) << e.what();
  }
  struct stat st {};
  ASSERT_EQ(::stat("/dev/full", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
}

// ---------------------------------------------------------------- class 3: YAML

// Nine anchors, each a map (or list) of nine aliases of the one before: 9^9 values expanded.
std::string AliasBomb(bool maps) {
  std::string y = maps ? "a0: &a0 {x: 1}\n" : "a0: &a0 [x]\n";
  for (int i = 1; i <= 9; ++i) {
    y += "a" + std::to_string(i) + ": &a" + std::to_string(i) + (maps ? " {" : " [");
    for (int k = 0; k < 9; ++k)
      y += (k ? ", " : "") + (maps ? "k" + std::to_string(k) + ": " : std::string()) + "*a" +
           std::to_string(i - 1);
    y += maps ? "}\n" : "]\n";
  }
  return y;
}

std::string IoErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const IoError& e) {
    return e.what();
  }
  return "";
}

TEST(HostileYaml, AliasBombsDeepNestingAndHugeFilesAreRefusedFast) {
  const fs::path d = FreshDir("hostile");
  const auto start = std::chrono::steady_clock::now();
  for (bool maps : {true, false}) {
    const std::string bomb = AliasBomb(maps);
    EXPECT_LT(bomb.size(), 1000u);
    Put(d / "bomb.yaml", bomb);
    const std::string f = (d / "bomb.yaml").string();
    for (const auto& read : std::vector<std::function<void()>>{
             [&] { ReadConfigScalars(f); }, [&] { ReadWeightsYaml(f); }, [&] { ReadBoxes(f); },
             [&] { ReadYamlFile(f); }}) {
      const std::string err = IoErrorOf(read);
      EXPECT_TRUE(Has(err, f + ": more than 100000 values once its aliases")) << err;
    }
  }
  const std::string deep = std::string(100, '[') + std::string(100, ']');
  EXPECT_TRUE(Has(IoErrorOf([&] { LoadYaml("a: " + deep, "deep.yaml"); }), "nested deeper"));
  const std::string deeper = std::string(5000, '[') + std::string(5000, ']');
  EXPECT_TRUE(Has(IoErrorOf([&] { LoadYaml(deeper, "deeper.yaml"); }), "deeper.yaml"));
  std::string block;
  for (int i = 0; i < 40; ++i) block += std::string(i, ' ') + "k" + std::to_string(i) + ":\n";
  EXPECT_TRUE(Has(IoErrorOf([&] { ParseConfigScalars(block + std::string(41, ' ') + "v: 1\n",
                                                     "block.yaml"); }),
                  "nested deeper"));
  Put(d / "huge.yaml", "a: " + std::string(2 << 20, 'x') + "\n");
  EXPECT_TRUE(Has(IoErrorOf([&] { ReadConfigScalars((d / "huge.yaml").string()); }),
                  "more than the"));
  EXPECT_TRUE(Has(IoErrorOf([&] { LoadYaml(std::string(2 << 20, ' '), "big.yaml"); }),
                  "more than the"));
  EXPECT_TRUE(Has(IoErrorOf([] { ReadConfigScalars("/dev/zero"); }), "/dev/zero"));
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 30.0);  // a bound on a hang, not a timing test: each case is refused early
}

TEST(HostileYaml, OddKeysAndValuesAreIoErrorsNamingTheFile) {
  for (const std::string& y : {std::string("? {a: 1}\n: 2\n"), std::string("? [a, b]\n: 2\n"),
                               std::string("a: !!binary AAAA\nb: [1, 2]\n"),
                               std::string("{a: 1, a: 2, [x]: 3}\n"), std::string("*x\n"),
                               std::string("a: &x 1\nb: *y\n"), std::string("\t- a\n"),
                               std::string("%YAML 9.9\n---\na: 1\n")}) {
    for (const auto& read : std::vector<std::function<void()>>{
             [&] { ParseConfigScalars(y, "odd.yaml"); }, [&] { ParseBoxes(y, "odd.json"); },
             [&] { ParseWeightsYaml(y, "odd.yaml"); }}) {
      try {
        read();
      } catch (const IoError& e) {
        EXPECT_TRUE(Has(e.what(), "odd.")) << e.what();
      } catch (const std::exception& e) {
        ADD_FAILURE() << y << ": not an IoError: " << e.what();
      }
    }
  }
}

TEST(HostileYaml, APipeWithoutWriterReadsAsEmptyInsteadOfHanging) {
  const fs::path d = FreshDir("hostile");
  const fs::path fifo = d / "config.yaml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_TRUE(Has(IoErrorOf([&] { ReadConfigScalars(fifo.string()); }), "is empty"));
}

// ---------------------------------------------------------------- class 4: outputs

TEST(HostileOutputs, DevicesAndPipesAreWrittenInPlaceNeverRenamedOver) {
  const fs::path d = FreshDir("hostile");
  WriteFileAtomic("/dev/null", "x\n");
  struct stat st {};
  ASSERT_EQ(::stat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  for (const auto& e : fs::directory_iterator("/dev"))
    EXPECT_FALSE(Has(e.path().filename().string(), ".null.tmp.")) << e.path();
  // A FIFO nobody reads: refused at once, not a hang, and still a FIFO.
  const fs::path fifo = d / "out.csv";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_TRUE(Has(IoErrorOf([&] { WriteFileAtomic(fifo.string(), "x\n"); }),
                  "a pipe that nobody reads"));
  // A FIFO with a reader gets the output.
  std::string got;
  std::thread reader([&] { got = Slurp(fifo); });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  std::string err;
  for (int i = 0; i < 50; ++i) {  // until the reader has opened its end
    err = IoErrorOf([&] { WriteFileAtomic(fifo.string(), "piped\n"); });
    if (err.empty()) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (!err.empty()) {  // let the reader go
    const int fd = ::open(fifo.c_str(), O_WRONLY);
    if (fd >= 0) ::close(fd);
  }
  reader.join();
  EXPECT_EQ(err, "");
  EXPECT_EQ(got, "piped\n");
  ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
}

TEST(HostileOutputs, LinksFoldersAndInputsAreHandledBeforeAnyWrite) {
  const fs::path d = FreshDir("hostile");
  Put(d / "target.csv", "old\n");
  fs::create_symlink("target.csv", d / "link.csv");
  WriteFileAtomic((d / "link.csv").string(), "new\n");
  EXPECT_TRUE(fs::is_symlink(d / "link.csv"));  // the link stays, its target is replaced
  EXPECT_EQ(Slurp(d / "target.csv"), "new\n");
  fs::create_symlink("missing/x.csv", d / "dangling.csv");
  EXPECT_TRUE(Has(IoErrorOf([&] { WriteFileAtomic((d / "dangling.csv").string(), "x"); }),
                  "leads nowhere"));
  EXPECT_TRUE(Has(IoErrorOf([&] { CheckOutputFile((d / "dangling.csv").string()); }),
                  "leads nowhere"));
  EXPECT_TRUE(Has(IoErrorOf([&] { CheckOutputFile(d.string()); }), "is a folder"));
  EXPECT_TRUE(Has(IoErrorOf([&] { CheckOutputFile((d / "no/such/x.csv").string()); }),
                  "does not exist"));
  for (const char* blk : {"/dev/loop0", "/dev/sda", "/dev/vda"}) {
    struct stat st {};
    if (::stat(blk, &st) == 0 && S_ISBLK(st.st_mode)) {
      EXPECT_TRUE(Has(IoErrorOf([&] { CheckOutputFile(blk); }), "a block device"));
      EXPECT_TRUE(Has(IoErrorOf([&] { WriteFileAtomic(blk, "x"); }), "a block device"));
    }
  }
  EXPECT_TRUE(Has(IoErrorOf([&] { CheckOutputFolder((d / "target.csv").string()); }),
                  "not a folder"));
  CheckOutputFolder((d / "new/deeper").string());  // made later: the folder above is writable
  // A hard link to an input is the input.
  fs::create_hard_link(d / "target.csv", d / "hard.csv");
  EXPECT_TRUE(Has(IoErrorOf([&] {
                    CheckOutputs({(d / "hard.csv").string()}, {(d / "target.csv").string()});
                  }),
                  "is also an input"));
  EXPECT_TRUE(Has(IoErrorOf([&] {
                    CheckOutputs({(d / "a.csv").string(), (d / "./a.csv").string()}, {});
                  }),
                  "given for two outputs"));
  // A bag is never written over a folder.
  fs::create_directories(d / "x.bag");
  try {
    BagWriter w((d / "x.bag").string(), BagWriterConfig{});
    ADD_FAILURE() << "no error";
  } catch (const BagError& e) {
    EXPECT_TRUE(Has(e.what(), "a folder has the bag's name")) << e.what();
  }
  EXPECT_FALSE(fs::exists(d / "x.bag.part"));
}

// ---------------------------------------------------------------- class 5: all or none

TEST(HostileAllOrNone, UncommittedBagsVanishAndFailedOutputsLeaveNothing) {
  const fs::path d = FreshDir("hostile");
  {
    BagWriter a((d / "a.bag").string(), MarkedConfig());
    a.Finish();  // complete, but the run failed before the commit
    EXPECT_TRUE(fs::exists(d / "a.bag.part"));
  }
  EXPECT_EQ(testing::CountFiles(d), 0);
  {
    BagWriter b((d / "b.bag").string(), MarkedConfig());
    b.Finish();
    b.Commit();
  }
  EXPECT_TRUE(fs::exists(d / "b.bag"));
  EXPECT_FALSE(fs::exists(d / "b.bag.part"));
  // The second output's folder is missing: the first is not written either.
  EXPECT_FALSE(IoErrorOf([&] {
                 WriteFilesAtomic({{(d / "one.csv").string(), "1"},
                                   {(d / "none/two.csv").string(), "2"}});
               }).empty());
  EXPECT_FALSE(fs::exists(d / "one.csv"));
  EXPECT_EQ(testing::CountFiles(d), 1);  // b.bag only: no temporary file left
}

TEST(HostileAllOrNone, ASignalRemovesRegisteredTemporaryFiles) {
  const fs::path d = FreshDir("hostile");
  const fs::path part = d / "x.bag.part";
  const int status = InChild([&] {
    InstallSignalCleanup();
    Put(part, "partial");
    RegisterTempFile(part.string());
    ::raise(SIGTERM);
    return 0;  // not reached
  });
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  EXPECT_FALSE(fs::exists(part));
  // During a commit the signal waits: the renames complete, then the process ends by it.
  const int committed = InChild([&] {
    InstallSignalCleanup();
    Put(part, "partial");
    RegisterTempFile(part.string());
    {
      const CommitScope scope;
      ::raise(SIGINT);
      fs::rename(part, d / "x.bag");
      UnregisterTempFile(part.string());
    }
    return 0;  // not reached
  });
  EXPECT_TRUE(WIFSIGNALED(committed));
  EXPECT_EQ(WTERMSIG(committed), SIGINT);
  EXPECT_TRUE(fs::exists(d / "x.bag"));
  EXPECT_FALSE(fs::exists(part));
}

// ---------------------------------------------------------------- class 6: numbers

const std::string kHeader =
    "bag,light,emitter,preset,distance_m,angle_deg,frames,mean_m,median_m,plane_std_m,"
    "hole_rate_pct,valid_pct,status\n";

TEST(HostileNumbers, MetricsCsvRefusesWhatTheManifestRefuses) {
  struct Case {
    std::string row;
    std::string says;
  };
  const std::vector<Case> cases = {
      {"a,d,on,HA,4,90,9,4,4,0.1,1,99,ok", "column 'angle_deg': 90 is outside (-90, 90) deg"},
      {"a,d,on,HA,4,-90,9,4,4,0.1,1,99,ok", "'angle_deg': -90 is outside"},
      {"a,d,on,HA,4,0,9,4,0,0.1,1,99,ok", "'median_m': 0 is outside (0, 1000] m"},
      {"a,d,on,HA,4,0,9,4,-5,0.1,1,99,ok", "'median_m': -5 is outside"},
      {"a,d,on,HA,4,0,9,4,1e300,0.1,1,99,ok", "'median_m': 1e+300 is outside"},
      {"a,d,on,HA,4,0,9,inf,4,0.1,1,99,ok", "'mean_m': 'inf' is not a finite number"},
      {"a,d,on,HA,0,0,9,4,4,0.1,1,99,ok", "'distance_m': 0 is outside"},
      {"a,d,on,HA,-4,0,9,4,4,0.1,1,99,ok", "'distance_m': -4 is outside"},
      {"a,d,on,HA,4,0,9.5,4,4,0.1,1,99,ok", "'frames': 9.5 is not a whole number"},
      {"a,d,on,HA,4,0,-1,4,4,0.1,1,99,ok", "'frames': -1 is outside"},
      {"a,d,on,HA,4,0,9,4,4,-0.1,1,99,ok", "'plane_std_m': -0.1 is outside"},
      {"a,d,on,HA,4,0,9,4,4,0.1,150,99,ok", "'hole_rate_pct': 150 is outside [0, 100] %"},
      {"a,d,on,HA,4,0,9,4,4,0.1,1,-1,ok", "'valid_pct': -1 is outside"},
      {"a,d,on,HA,4,0,9,4,,0.1,1,99,ok", "median_m"},
  };
  for (const auto& c : cases) {
    const std::string err = IoErrorOf([&] { ParseMetricsCsv(kHeader + c.row + "\n", "m.csv"); });
    EXPECT_TRUE(Has(err, "m.csv:2: ")) << c.row << ": " << err;
    EXPECT_TRUE(Has(err, c.says)) << c.row << ": " << err;
  }
  // Empty cells stay allowed where they mean "not measured": a failed row, no ground truth.
  const auto rows = ParseMetricsCsv(kHeader + "a,d,on,HA,,,0,,,,100,0,no_panel\n", "m.csv");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_TRUE(std::isnan(rows[0].median_m));
  // The same rules in the manifest.
  EXPECT_TRUE(Has(IoErrorOf([] {
                    ParseManifest("bag,distance_m,angle_deg,light\nx.bag,4,90,d\n", "m.csv");
                  }),
                  "90 is outside (-90, 90) deg"));
  EXPECT_TRUE(Has(IoErrorOf([] {
                    ParseManifest("bag,distance_m,angle_deg,light\nx.bag,1e6,0,d\n", "m.csv");
                  }),
                  "1e+06 is outside (0, 1000] m"));
}

std::string WeightsWith(const std::string& residual, const std::string& covariance) {
  return "schema: depthbias.weights/1\nmodel: paper6\nlambda: 0.001\nfocal_px: 640\n"
         "baseline_m: 0.095\ngroups:\n  - light: daylight\n    preset: HA\n    n: 32\n"
         "    weights: {w0: 0.1, w1: 0.01, w2: 0.001, w3: 0.1, w4: 0.1, w5: 0.01}\n"
         "    rmse_m: 0.5\n    mae_m: 0.4\n    residual_std_m: " +
         residual + "\n" + covariance;
}

std::string Diagonal(const std::vector<std::string>& d, const std::string& off = "0") {
  std::string c = "    covariance:\n";
  for (size_t i = 0; i < d.size(); ++i) {
    c += "      - [";
    for (size_t j = 0; j < d.size(); ++j) c += (j ? ", " : "") + (i == j ? d[i] : off);
    c += "]\n";
  }
  return c;
}

TEST(HostileNumbers, WeightsWhoseMarginWouldShrinkAreRefused) {
  const std::vector<std::string> ok(6, "0.01");
  EXPECT_EQ(IoErrorOf([&] { ParseWeightsYaml(WeightsWith("0.5", Diagonal(ok)), "w.yaml"); }), "");
  // An unknown covariance is written as an empty list and reads back (found by fuzz_weights_yaml:
  // the range checks first refused it, so a fit without covariance could not be read).
  EXPECT_EQ(IoErrorOf([&] { ParseWeightsYaml(WeightsWith("0.5", "    covariance: []\n"), "w.yaml"); }),
            "");
  // NaN scatter: unknown (n <= p), read, and the model then claims no margin (see apps test).
  EXPECT_EQ(IoErrorOf([&] { ParseWeightsYaml(WeightsWith(".nan", ""), "w.yaml"); }), "");
  struct Case {
    std::string yaml;
    std::string says;
  };
  std::vector<std::string> negative = ok;
  negative[2] = "-0.2";
  std::vector<std::string> nan_var = ok;
  nan_var[1] = ".nan";
  const std::vector<Case> cases = {
      {WeightsWith("-0.5", ""), "residual_std_m': -0.5 is outside [0, inf) m"},
      {WeightsWith(".inf", ""), "residual_std_m': inf is not a finite number"},
      {WeightsWith("0.5", Diagonal(negative)), "covariance[2][2]': -0.2 is a negative variance"},
      {WeightsWith("0.5", Diagonal(nan_var)), "covariance[1][1]': nan is not a finite number"},
      {WeightsWith("0.5", Diagonal(ok, "0.5")), "exceeds the square root"},
      {WeightsWith("0.5", Diagonal({"0.01", "0.01"})), "has 2 rows, expected 6 x 6"},
      {WeightsWith("0.5", "").replace(WeightsWith("0.5", "").find("lambda: 0.001"), 13,
                                      "lambda: -1"),
       "lambda': -1 is outside"},
      {WeightsWith("0.5", "").replace(WeightsWith("0.5", "").find("n: 32"), 5, "n: 0"),
       "n': 0 rows"},
      {WeightsWith("0.5", "").replace(WeightsWith("0.5", "").find("w0: 0.1"), 7, "w0: .nan"),
       "w0': nan is not a finite number"},
  };
  for (const auto& c : cases) {
    const std::string err = IoErrorOf([&] { ParseWeightsYaml(c.yaml, "w.yaml"); });
    EXPECT_TRUE(Has(err, "w.yaml: key '")) << err;
    EXPECT_TRUE(Has(err, c.says)) << c.says << " | " << err;
  }
  // Asymmetric.
  std::string asym = Diagonal(ok);
  asym.replace(asym.find("0.01, 0, 0"), 10, "0.01, 0.001, 0");
  EXPECT_TRUE(Has(IoErrorOf([&] { ParseWeightsYaml(WeightsWith("0.5", asym), "w.yaml"); }),
                  "not symmetric"));
}

// ---------------------------------------------------------------- class 7: directory scans

TEST(HostileScan, WhatASearchCannotReadIsListedWithItsReason) {
  const fs::path d = FreshDir("hostile");
  Put(d / "good.bag", "x");
  fs::create_symlink("missing.bag", d / "dangling.bag");
  fs::create_symlink("loop_b.bag", d / "loop_a.bag");
  fs::create_symlink("loop_a.bag", d / "loop_b.bag");
  ASSERT_EQ(::mkfifo((d / "fifo.bag").c_str(), 0600), 0);
  fs::create_directories(d / "folder.bag");
  fs::create_directories(d / "sub");
  Put(d / "sub/deep.bag", "x");
  fs::create_directory_symlink("..", d / "sub/up");  // a loop through a folder link: searched once
  Put(d / "notes.txt", "x");
  const auto listed = ListBags({d.string()});
  std::map<std::string, std::string> by_name;
  for (const auto& l : listed) by_name[fs::path(l.path).filename().string()] = l.problem;
  EXPECT_EQ(by_name.size(), listed.size()) << "listed twice";
  EXPECT_EQ(by_name.count("good.bag"), 1u);
  EXPECT_EQ(by_name["good.bag"], "");
  EXPECT_EQ(by_name["deep.bag"], "");
  EXPECT_TRUE(Has(by_name["dangling.bag"], "leads nowhere")) << by_name["dangling.bag"];
  EXPECT_TRUE(Has(by_name["loop_a.bag"], "loop")) << by_name["loop_a.bag"];
  EXPECT_TRUE(Has(by_name["fifo.bag"], "a pipe")) << by_name["fifo.bag"];
  EXPECT_TRUE(Has(by_name["folder.bag"], "folder")) << by_name["folder.bag"];
  EXPECT_EQ(by_name.count("notes.txt"), 0u);
  // An unreadable sub-folder is listed with the reason (as another user when run as root,
  // whom permissions do not stop).
  fs::create_directories(d / "locked");
  Put(d / "locked/hidden.bag", "x");
  ::chmod((d / "locked").c_str(), 0);
  const int status = InChild([&] {
    if (::geteuid() == 0) {
      ::chmod(d.c_str(), 0755);
      if (::setgid(65534) != 0 || ::setuid(65534) != 0) return 10;
      // A checkout in a private folder (mktemp -d: 0700) keeps the other user out of the
      // whole tree, not only the locked folder.
      if (::access(d.c_str(), R_OK | X_OK) != 0) return 12;
    }
    for (const auto& l : ListBags({d.string()}))
      if (fs::path(l.path).filename() == "locked" && Has(l.problem, "Permission denied"))
        return 0;
    return 11;
  });
  ::chmod((d / "locked").c_str(), 0755);
  ASSERT_TRUE(WIFEXITED(status));
  if (WEXITSTATUS(status) == 10) GTEST_SKIP() << "cannot become another user";
  if (WEXITSTATUS(status) == 12) GTEST_SKIP() << "another user cannot reach " << d;
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

// ---------------------------------------------------------------- class 8: numbers in text

TEST(HostileText, NumbersInMessagesAreWrittenAsPeopleWriteThem) {
  EXPECT_EQ(records::SizeText(1.0, 1.0, "m"), "1 x 1 m");
  EXPECT_EQ(records::NumberText(0.25), "0.25");
  EXPECT_EQ(records::NumberText(1e-300), "1e-300");
  EXPECT_EQ(records::NumberText(640.0), "640");
  EXPECT_EQ(records::BytesText(9.2e9), "9.2 GB");
  EXPECT_EQ(rules::kAngleDeg.Interval(), "(-90, 90) deg");
}

}  // namespace
}  // namespace depthbias::io
