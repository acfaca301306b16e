#include "io/recording.h"

#include <sys/stat.h>

#include <cstring>
#include <fstream>

#include "io/bag_summary.h"
#include "io/mcap_records.h"
#include "io/rosbag2_source.h"

namespace depthbias::io {
namespace {

bool EndsWith(const std::string& s, const char* tail) {
  const std::size_t n = std::strlen(tail);
  return s.size() >= n && s.compare(s.size() - n, n, tail) == 0;
}

// A RealSense ROS 1 bag through BagReader (Rewind opens it again).
class Ros1Recording : public RecordingSource {
 public:
  Ros1Recording(const std::string& path, const RecordingOptions& options)
      : RecordingSource(RecordingFormat::kRos1Bag), path_(path), options_(options) {
    Rewind();
  }
  bool Next(records::DepthFrame* frame) override { return reader_->Next(frame); }
  bool Rewind() override {
    reader_ = std::make_unique<BagReader>(path_, ReadOptions{options_.allow_partial});
    info_ = reader_->info();
    return true;
  }
  std::string damage() const override { return reader_->damage(); }
  std::string settings_source() const override {
    return info_.options.count("Visual_Preset") ? "recorded options" : "";
  }
  std::string SummaryText() const override { return BagSummaryText(info_); }
  std::string SummaryJson() const override { return BagSummaryJson(info_); }

 private:
  std::string path_;
  RecordingOptions options_;
  std::unique_ptr<BagReader> reader_;
};

}  // namespace

std::string RecordingSource::format_name() const {
  switch (format_) {
    case RecordingFormat::kRos1Bag: return "ROS 1 bag";
    case RecordingFormat::kRosbag2Folder: return "rosbag2 folder";
    case RecordingFormat::kMcap: return "rosbag2 MCAP file";
    case RecordingFormat::kSqlite: return "rosbag2 SQLite3 file";
  }
  return "";
}

RecordingFormat FormatOf(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
    struct stat meta {};
    if (::stat((path + "/metadata.yaml").c_str(), &meta) == 0)
      return RecordingFormat::kRosbag2Folder;
    return RecordingFormat::kRos1Bag;  // reading it says it is a folder
  }
  if (EndsWith(path, ".mcap")) return RecordingFormat::kMcap;
  if (EndsWith(path, ".db3")) return RecordingFormat::kSqlite;
  if (S_ISREG(st.st_mode)) {
    char head[8] = {};
    std::ifstream in(path, std::ios::binary);
    if (in.read(head, 8) && std::memcmp(head, mcap::kMagic, 8) == 0) return RecordingFormat::kMcap;
  }
  return RecordingFormat::kRos1Bag;
}

std::unique_ptr<RecordingSource> OpenRecording(const std::string& path,
                                               const RecordingOptions& options) {
  const RecordingFormat format = FormatOf(path);
  if (format == RecordingFormat::kRos1Bag) return std::make_unique<Ros1Recording>(path, options);
  return OpenRosbag2(path, format, options);
}

}  // namespace depthbias::io
