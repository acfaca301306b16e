#pragma once
// Every recording a tool reads, whatever wrote it, as one frame source: the one function every
// tool calls to open a recording, chosen by what the path is.
//   - a folder holding metadata.yaml: a rosbag2 recording (its storage files in order);
//   - a file ending in .mcap, or starting with MCAP's magic: a bare rosbag2 MCAP file;
//   - a file ending in .db3: a bare rosbag2 SQLite3 file;
//   - anything else: a RealSense ROS 1 bag (io/bag.h), as before.
// A ROS 2 recording's depth topic, camera_info and recorded parameters fill the same BagInfo a
// ROS 1 bag gives (the depth sensor's Visual_Preset and Emitter_Enabled among its options when
// the RealSense wrapper's parameters were recorded).

#include <memory>
#include <string>

#include "io/bag.h"
#include "records/frame_source.h"

namespace depthbias::io {

enum class RecordingFormat { kRos1Bag, kRosbag2Folder, kMcap, kSqlite };

struct RecordingOptions {
  std::string topic;           // the depth topic of a ROS 2 recording; "" finds it
  bool allow_partial = false;  // ROS 1: read a damaged bag up to the damage (ReadOptions)
};

class RecordingSource : public records::FrameSource {
 public:
  const BagInfo& info() const { return info_; }
  // Where the recording stopped being readable ("" when whole); a bare MCAP file cut short is
  // read up to its last whole record and says so here.
  virtual std::string damage() const { return ""; }
  // Where the preset and emitter in info().options came from: "recorded options" (a ROS 1
  // bag), "parameter messages" (a ROS 2 recording with the wrapper's parameters), or "" when
  // the recording holds neither (the manifest must give them).
  virtual std::string settings_source() const = 0;
  virtual std::string SummaryText() const = 0;  // what bag_info prints
  virtual std::string SummaryJson() const = 0;  // one JSON object, one line
  std::string format_name() const;

 protected:
  explicit RecordingSource(RecordingFormat format) : format_(format) {}
  BagInfo info_;
  RecordingFormat format_;
};

// What the path is (see above). A missing path is a ROS 1 bag (reading it says it is missing).
RecordingFormat FormatOf(const std::string& path);

// Opens the recording at path. Throws BagError (one line naming the file) on anything a
// recording cannot be read for, IoError for a bad metadata.yaml.
std::unique_ptr<RecordingSource> OpenRecording(const std::string& path,
                                               const RecordingOptions& options = {});

}  // namespace depthbias::io
