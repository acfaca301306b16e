#pragma once
// A fresh folder per test under the build tree, removed at the end.

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace depthbias::io::testing {

inline std::filesystem::path FreshDir(const std::string& tag) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::filesystem::path dir = std::filesystem::path(DEPTHBIAS_BINARY_DIR) / "test_tmp" /
                              (tag + "_" + info->test_suite_name() + "_" + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// Files in a folder (to check no temporary file is left behind).
inline int CountFiles(const std::filesystem::path& dir) {
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    (void)e;
    ++n;
  }
  return n;
}

}  // namespace depthbias::io::testing
