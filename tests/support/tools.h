#pragma once
// The project's tools run from tests as a user runs them: where they are built, and one run's
// exit status and output.

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace depthbias::test_support {

// The path of tool `app`: in $DEPTHBIAS_BIN (ctest sets it), else in the build tree's apps/.
inline std::string Bin(const std::string& app) {
  const char* b = std::getenv("DEPTHBIAS_BIN");
  return std::string(b ? b : DEPTHBIAS_BINARY_DIR "/apps") + "/" + app;
}

// A whole file, byte for byte ("" when it cannot be read).
inline std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct ToolRun {
  int code = -1;  // exit status; 128 + N when ended by signal N; -1 when no shell ran
  std::string out, err;
};

// Runs a shell command line with its standard output and error caught in dir/stdout.txt and
// dir/stderr.txt (left there for whoever reads a failed test).
inline ToolRun RunShell(const std::string& command, const std::filesystem::path& dir) {
  const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  const int status =
      std::system((command + " > " + out.string() + " 2> " + err.string()).c_str());
  ToolRun r;
  if (WIFEXITED(status)) r.code = WEXITSTATUS(status);
  else if (WIFSIGNALED(status)) r.code = 128 + WTERMSIG(status);
  r.out = ReadFile(out);
  r.err = ReadFile(err);
  return r;
}

}  // namespace depthbias::test_support
