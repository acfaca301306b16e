#include "io/atomic_file.h"

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>

#include "io/entry_store.h"
#include "io/sha256.h"
#include "test_dir.h"

namespace depthbias::io {
namespace {

using testing::CountFiles;
using testing::FreshDir;

TEST(AtomicFile, WritesAndReplacesWithoutLeavingTemporaries) {
  const auto dir = FreshDir("io");
  const std::string path = (dir / "out.txt").string();
  WriteFileAtomic(path, "first");
  EXPECT_EQ(ReadFile(path), "first");
  WriteFileAtomic(path, std::string(100000, 'x'));
  EXPECT_EQ(ReadFile(path).size(), 100000u);
  EXPECT_EQ(CountFiles(dir), 1);
}

TEST(AtomicFile, MissingFolderFailsAndNamesThePath) {
  const auto dir = FreshDir("io");
  const std::string path = (dir / "no_such_folder" / "out.txt").string();
  try {
    WriteFileAtomic(path, "x");
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(AtomicFile, FolderAsOutputIsRefused) {
  const auto dir = FreshDir("io");
  EXPECT_THROW(WriteFileAtomic(dir.string(), "x"), IoError);
  EXPECT_EQ(CountFiles(dir), 0);
}

TEST(AtomicFile, ReadMissingFileNamesIt) {
  try {
    ReadFile("/nonexistent/file.csv");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/file.csv"), std::string::npos);
  }
}

TEST(AtomicFile, SameFileSeesThroughOtherSpellings) {
  const auto dir = FreshDir("io");
  WriteFileAtomic((dir / "a.csv").string(), "x");
  EXPECT_TRUE(SameFile((dir / "a.csv").string(), (dir / "." / "a.csv").string()));
  EXPECT_FALSE(SameFile((dir / "a.csv").string(), (dir / "b.csv").string()));
}

// The outputs of one run are written together: when one cannot be written, none is.
TEST(AtomicFile, SeveralOutputsAreAllOrNothing) {
  const auto dir = FreshDir("io");
  const std::string a = (dir / "a.csv").string(), b = (dir / "b.json").string();
  WriteFilesAtomic({{a, "one"}, {b, "two"}});
  EXPECT_EQ(ReadFile(a), "one");
  EXPECT_EQ(ReadFile(b), "two");
  const std::string missing = (dir / "no_such_folder" / "c.json").string();
  try {
    WriteFilesAtomic({{a, "changed"}, {missing, "x"}});
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadFile(a), "one");  // left as it was
  EXPECT_EQ(CountFiles(dir), 2);  // no temporary left
}

TEST(AtomicFile, AnOutputNeverOverwritesAnInput) {
  const auto dir = FreshDir("io");
  const std::string in = (dir / "in.csv").string();
  WriteFileAtomic(in, "x");
  const std::string same = (dir / "." / "in.csv").string();
  try {
    CheckOutputs({(dir / "out.csv").string(), same}, {"", in});
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("is also an input"), std::string::npos) << e.what();
  }
  // Two outputs on one path, whether or not it exists yet.
  EXPECT_THROW(CheckOutputs({(dir / "o.csv").string(), (dir / "." / "o.csv").string()}, {}),
               IoError);
  EXPECT_NO_THROW(CheckOutputs({(dir / "out.csv").string(), ""}, {in, ""}));
}

TEST(AtomicFile, BaseNameDropsFolders) {
  EXPECT_EQ(BaseName("a/b/c.bag"), "c.bag");
  EXPECT_EQ(BaseName("c.bag"), "c.bag");
}

// FIPS 180-4 test vectors.
TEST(Sha256, KnownVectors) {
  EXPECT_EQ(Sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(Sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(Sha256Hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

// Two runs writing the same pair of outputs at once (the CSV and the panels JSON of
// panel_extract): each commits its pair as one, so a reader holding the set's lock only ever sees
// one run's pair, and what is left in place is one run's pair, never the CSV of one and the JSON
// of the other.
TEST(AtomicFile, TwoRunsWritingTheSameSetNeverLeaveAMixedPair) {
  const auto dir = FreshDir("io");
  const std::string a = (dir / "m.csv").string(), b = (dir / "p.json").string();
  WriteFilesAtomic({{a, "start"}, {b, "start"}});
  pid_t kids[2];
  for (int w = 0; w < 2; ++w) {
    kids[w] = ::fork();
    ASSERT_GE(kids[w], 0);
    if (kids[w] == 0) {
      for (int i = 0; i < 400; ++i) {
        const std::string tag = std::to_string(w) + ":" + std::to_string(i);
        WriteFilesAtomic({{a, tag + " csv"}, {b, tag + " json"}});
      }
      ::_exit(0);
    }
  }
  auto stem = [](const std::string& text) { return text.substr(0, text.find(' ')); };
  int seen = 0, mixed = 0, running = 2;
  while (running > 0) {
    {
      const OutputSetLock lock({a, b});
      const std::string ca = ReadFile(a), cb = ReadFile(b);
      ++seen;
      if (stem(ca) != stem(cb)) ++mixed;
    }
    running = 0;
    for (pid_t k : kids) running += ::waitpid(k, nullptr, WNOHANG) == 0 ? 1 : 0;
  }
  for (pid_t k : kids) ::waitpid(k, nullptr, 0);
  EXPECT_GT(seen, 0);
  EXPECT_EQ(mixed, 0) << "of " << seen << " looks";
  EXPECT_EQ(stem(ReadFile(a)), stem(ReadFile(b)));
  EXPECT_EQ(CountFiles(dir), 2);  // no temporary file left
}

// A folder of entries kept between runs: a missing entry or folder is no error, an entry is
// written whole with its folder made first, and something that is not a file is refused by name.
TEST(EntryStore, ReadsWhatItWroteAndTellsAMissingEntry) {
  const auto dir = FreshDir("io");
  const std::string folder = (dir / "kept" / "deeper").string();
  std::string bytes = "unchanged";
  EXPECT_FALSE(ReadEntry(folder, "a.sims", 1 << 20, &bytes));
  EXPECT_EQ(bytes, "unchanged");
  WriteEntry(folder, "a.sims", std::string("\0bytes\n", 7));
  ASSERT_TRUE(ReadEntry(folder, "a.sims", 1 << 20, &bytes));
  EXPECT_EQ(bytes, std::string("\0bytes\n", 7));
  std::filesystem::create_directories(std::filesystem::path(folder) / "b.sims");
  try {
    ReadEntry(folder, "b.sims", 1 << 20, &bytes);
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("b.sims"), std::string::npos) << e.what();
  }
  EXPECT_THROW(WriteEntry((dir / "kept" / "deeper" / "a.sims").string(), "c.sims", "x"),
               IoError);  // a file where the folder should be
}

// The program as files: its executable and the shared libraries it runs with, each with its
// SHA-256, in path order.
TEST(EntryStore, ProgramFilesDigestNamesTheExecutableAndItsLibraries) {
  const std::string digest = ProgramFilesDigest();
  std::istringstream in(digest);
  int lines = 0, libraries = 0;
  bool executable = false;
  std::string last;
  for (std::string line; std::getline(in, line); ++lines) {
    ASSERT_GT(line.size(), 66u) << line;
    EXPECT_EQ(line.find_first_not_of("0123456789abcdef"), 64u) << line;
    const std::string path = line.substr(65);
    EXPECT_LT(last, path);
    last = path;
    executable = executable || path == std::filesystem::read_symlink("/proc/self/exe").string();
    libraries += path.find(".so") != std::string::npos;
  }
  EXPECT_TRUE(executable) << digest;
  EXPECT_GE(libraries, 2) << digest;  // the C and C++ runtimes at least
}

}  // namespace
}  // namespace depthbias::io
