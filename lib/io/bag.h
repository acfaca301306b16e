#pragma once
// RealSense ROS1 bag layout (as librealsense's recorder writes it): reading the depth stream,
// its intrinsics, depth units, recorded options and device info; and writing the same layout.
// Both go through Debian's rosbag_storage. The reader opens the bag with rosbag::Bag, reads the
// metadata topics and then the depth frames through rosbag::View, one frame at a time (memory
// holds rosbag's small per-message index and one chunk, however long the bag), and decodes the
// messages with roscpp_serialization, including the depth units librealsense appends to each
// image. Before rosbag sees a file, a structural check of its records (no decompression) turns
// damage rosbag would not survive into a BagError; the only reads that do not go through rosbag
// are partial reads of a bag rosbag cannot open (see ReadOptions).

#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "records/depth_frame.h"
#include "camera/intrinsics.h"

namespace depthbias::io {

// Every failure to read or write a bag. what() is one line naming the file and what is wrong.
class BagError : public std::runtime_error {
 public:
  enum class Kind {
    kNotFound,       // no such path
    kNotAFile,       // a directory or other non-regular file
    kEmpty,          // zero-length file
    kNotABag,        // not a ROS1 bag
    kTruncated,      // ends in the middle of a record or chunk
    kCorrupt,        // a chunk or record that cannot be decoded
    kNoDepthStream,  // a bag without a depth stream
    kBadEncoding,    // depth stream in another encoding than 16-bit depth
    kWrite,          // could not write
  };
  BagError(Kind kind, const std::string& file, const std::string& what);
  Kind kind() const { return kind_; }
  const std::string& file() const { return file_; }

 private:
  Kind kind_;
  std::string file_;
};

// One recorded stream (depth, color, infrared, IMU, ...).
struct StreamInfo {
  std::string topic;        // e.g. /device_0/sensor_0/Depth_0/image/data
  int sensor_index = -1;    // n in /device_0/sensor_<n>
  std::string stream_type;  // "Depth", "Color", "Infrared", "Accel", "Gyro", ...
  int stream_index = 0;     // the number after the type (Depth_0)
  std::string encoding;     // e.g. mono16, rgb8; empty for non-image streams
  int width = 0;
  int height = 0;
  int fps = 0;              // nominal rate [Hz], 0 when not recorded
  std::uint64_t messages = 0;
};

struct BagInfo {
  std::string file;
  bool compressed = false;            // LZ4 or BZ2 chunks
  bool indexed = true;                // false when read without its index (partial read)
  std::vector<StreamInfo> streams;
  StreamInfo depth;                   // the depth stream
  camera::Intrinsics depth_intrinsics;
  bool has_depth_intrinsics = false;  // false when the bag holds no camera_info for the stream
  double depth_units_m = 0.001;       // the first frame's own units, else Depth_Units, else 0.001
  std::uint64_t depth_frames = 0;
  double first_timestamp_ms = 0.0;    // device timestamps of the first and last depth frames
  double last_timestamp_ms = 0.0;
  // The depth sensor's recorded options as of its first frame, names as recorded
  // (Visual_Preset, Emitter_Enabled, Laser_Power, Depth_Units, ...); values are float32 in
  // the bag. On the D455 Visual_Preset 3 is High Accuracy and 4 is High Density.
  std::map<std::string, double> options;
  std::map<std::string, std::string> option_descriptions;
  std::map<std::string, std::string> sensor;   // depth sensor's info ("Name", ...)
  std::map<std::string, std::string> device;   // "Name", "Serial Number", "Firmware Version", ...
};


// Points ROS_HOME at a private temporary folder when rospack could not write its cache in
// ~/.ros (it would print warnings on stderr). Called before rosbag is first used; apps call it
// at the start of main, before any thread starts (setenv is not thread-safe).
void PrepareRosEnvironment();

struct ReadOptions {
  // On damage, stop at the last good frame instead of throwing. A bag rosbag cannot open (no
  // index because it was cut short or never closed, or damage found by the structural check) is
  // then read by scanning its chunks in file order up to the damage, without rosbag;
  // info().indexed is false and damage() says what was wrong.
  bool allow_partial = false;
};

class BagReader {
 public:
  // Opens the bag and reads its index, streams, intrinsics, options and device info.
  // Throws BagError.
  explicit BagReader(const std::string& path, ReadOptions options = {});
  ~BagReader();
  BagReader(const BagReader&) = delete;
  BagReader& operator=(const BagReader&) = delete;

  const BagInfo& info() const;

  // Next depth frame in recorded order; false at the end. Throws BagError on damage unless
  // allow_partial, in which case it returns false and damage() says what was wrong.
  bool Next(records::DepthFrame* frame);
  const std::string& damage() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct BagWriterConfig {
  camera::Intrinsics intrinsics = camera::D455::DepthIntrinsics();
  double depth_units_m = 0.001;               // recorded as the Depth_Units option [m]
  double fps = 30.0;
  bool compress_lz4 = false;                  // the D455 records uncompressed by default
  std::map<std::string, double> options;      // e.g. Visual_Preset, Emitter_Enabled (float32)
  std::map<std::string, std::string> device;  // Name, Serial Number, Firmware Version

  bool IsValid(std::string* why) const;
};

// Writes a depth-only bag in the layout librealsense's recorder writes and its playback reads
// (device 0, sensor 0 "Stereo Module", stream Depth_0, mono16). Each frame keeps its own depth
// units, number and device timestamp. The bag is written to PATH.part (removed on SIGINT and
// SIGTERM once io::InstallSignalCleanup ran) and renamed at Close(), or at Commit() after
// Finish(); a writer destroyed before that (an error unwound past it, or a later recording of
// the same run failed) removes PATH.part. A PATH that exists and is not a regular file (a
// folder, a device) is refused at construction. A full disk is a BagError, never an abort.
class BagWriter {
 public:
  BagWriter(const std::string& path, BagWriterConfig config);  // throws BagError
  ~BagWriter();
  BagWriter(const BagWriter&) = delete;
  BagWriter& operator=(const BagWriter&) = delete;

  void Write(const records::DepthFrame& frame);  // throws BagError
  void Close();                                 // Finish() then Commit(); throws BagError
  // Completes the bag at PATH.part without renaming it: a run renames its bags together, all
  // or none, with Commit() once every recording is finished.
  void Finish();  // throws BagError
  void Commit();  // throws BagError

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace depthbias::io
