#include "io/rosbag2_source.h"

#include <sys/stat.h>

#include <algorithm>
#include <set>

#include "io/io_error.h"
#include "io/ros2_messages.h"
#include "io/rosbag2_metadata.h"

namespace depthbias::io {

const char* const kWrapperDepthTopics[4] = {
    "/camera/camera/depth/image_rect_raw", "/camera/depth/image_rect_raw",
    "/camera/camera/aligned_depth_to_color/image_raw", "/camera/aligned_depth_to_color/image_raw"};

std::string Rosbag2SummaryText(const BagInfo& info, const Rosbag2Info& r2,
                               const std::string& settings, const std::string& damage);
std::string Rosbag2SummaryJson(const BagInfo& info, const Rosbag2Info& r2,
                               const std::string& settings, const std::string& damage);

namespace {

bool EndsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

std::string Parent(const std::string& topic) {
  const std::size_t slash = topic.rfind('/');
  return slash == std::string::npos ? "" : topic.substr(0, slash);
}

std::uint64_t FileSize(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? static_cast<std::uint64_t>(st.st_size) : 0;
}

class Rosbag2Source : public RecordingSource {
 public:
  Rosbag2Source(const std::string& path, RecordingFormat format, const RecordingOptions& options)
      : RecordingSource(format), path_(path), options_(options) {
    Open();
  }

  bool Next(records::DepthFrame* frame) override {
    Ros2Message m;
    while (storage_->Next(depth_set_, &m)) {
      ros2::Image image;
      std::string why;
      if (!ros2::DecodeImage(m.data, m.size, &image, &why) ||
          !ros2::ImageToDepthFrame(image, info_.depth_units_m, frame, &why))
        throw BagError(why.find("encoding") != std::string::npos ? BagError::Kind::kBadEncoding
                                                                 : BagError::Kind::kCorrupt,
                       path_, r2_.depth_topic + " message " + std::to_string(frames_ + 1) +
                                  ": " + why);
      if (frame->width != info_.depth.width || frame->height != info_.depth.height)
        throw BagError(BagError::Kind::kCorrupt, path_,
                       r2_.depth_topic + " message " + std::to_string(frames_ + 1) + ": " +
                           std::to_string(frame->width) + "x" + std::to_string(frame->height) +
                           " px in a stream of " + std::to_string(info_.depth.width) + "x" +
                           std::to_string(info_.depth.height) + " px");
      frame->frame_number = ++frames_;
      return true;
    }
    return false;
  }
  bool Rewind() override {
    storage_->Rewind();
    frames_ = 0;
    return true;
  }
  std::string damage() const override { return storage_->damage(); }
  std::string settings_source() const override { return settings_; }
  std::string SummaryText() const override {
    return Rosbag2SummaryText(info_, r2_, settings_, damage());
  }
  std::string SummaryJson() const override {
    return Rosbag2SummaryJson(info_, r2_, settings_, damage());
  }
  const Rosbag2Info& r2() const { return r2_; }

 private:
  [[noreturn]] void Fail(BagError::Kind kind, const std::string& what) const {
    throw BagError(kind, path_, what);
  }
  void Open();
  void OpenStorage();
  void ChooseTopics();
  void ReadSettings();

  std::string path_;
  RecordingOptions options_;
  std::unique_ptr<Ros2Storage> storage_;
  Rosbag2Info r2_;
  std::string settings_;
  std::set<std::size_t> depth_set_;
  std::size_t depth_ = 0;
  int info_topic_ = -1, param_topic_ = -1;
  std::uint64_t frames_ = 0;
};

void Rosbag2Source::OpenStorage() {
  std::vector<std::unique_ptr<Ros2Storage>> parts;
  if (format_ == RecordingFormat::kRosbag2Folder) {
    Rosbag2Metadata meta;
    try {
      meta = ReadRosbag2Metadata(path_ + "/metadata.yaml");
    } catch (const IoError& e) {
      Fail(BagError::Kind::kNotABag, e.what());
    }
    r2_.has_metadata = true;
    if (!meta.compression_mode.empty() && meta.compression_mode != "NONE")
      Fail(BagError::Kind::kNotABag,
           "metadata.yaml: compression_mode " + meta.compression_mode + " (" +
               meta.compression_format +
               ") is not read; record with MCAP chunk compression "
               "(--storage-preset-profile zstd_fast) or decompress with ros2 bag convert");
    for (const std::string& name : meta.relative_file_paths) {
      const std::string file = path_ + "/" + name;
      const bool db3 = meta.storage_identifier == "sqlite3" || EndsWith(name, ".db3");
      if (!db3 && meta.storage_identifier != "mcap" && !EndsWith(name, ".mcap"))
        Fail(BagError::Kind::kNotABag, "metadata.yaml: storage '" +
                                           meta.storage_identifier.substr(0, 32) +
                                           "' (mcap or sqlite3 expected)");
      parts.push_back(db3 ? OpenSqliteStorage(file) : OpenMcapStorage(file));
      r2_.files.push_back(file);
    }
  } else {
    parts.push_back(format_ == RecordingFormat::kSqlite ? OpenSqliteStorage(path_)
                                                        : OpenMcapStorage(path_));
    r2_.files.push_back(path_);
  }
  for (const std::string& f : r2_.files) r2_.bytes += FileSize(f);
  storage_ = ChainStorages(std::move(parts));
  r2_.storage = storage_->storage();
  r2_.compression = storage_->compression();
  r2_.topics = storage_->topics();
  r2_.start_ns = storage_->start_ns();
  r2_.end_ns = storage_->end_ns();
}

void Rosbag2Source::ChooseTopics() {
  const std::vector<Ros2Topic>& topics = r2_.topics;
  auto find = [&](const std::string& name) -> int {
    for (std::size_t i = 0; i < topics.size(); ++i)
      if (topics[i].name == name) return static_cast<int>(i);
    return -1;
  };
  int depth = -1;
  if (!options_.topic.empty()) {
    depth = find(options_.topic);
    if (depth < 0) Fail(BagError::Kind::kNoDepthStream, "no topic " + options_.topic);
    if (topics[depth].type != ros2::kImageType)
      Fail(BagError::Kind::kNoDepthStream,
           options_.topic + " is a " + topics[depth].type + ", not a " + ros2::kImageType);
    r2_.depth_topic_why = "given with --topic";
  }
  for (const char* name : kWrapperDepthTopics) {
    if (depth >= 0) break;
    const int i = find(name);
    if (i >= 0 && topics[i].type == ros2::kImageType) {
      depth = i;
      r2_.depth_topic_why = "the RealSense wrapper's name";
    }
  }
  if (depth < 0) {  // any image topic named like depth: exactly one, or ask for --topic
    std::vector<int> named;
    for (std::size_t i = 0; i < topics.size(); ++i)
      if (topics[i].type == ros2::kImageType &&
          topics[i].name.find("depth") != std::string::npos)
        named.push_back(static_cast<int>(i));
    if (named.size() > 1) {
      std::string list;
      for (int i : named) list += " " + topics[i].name;
      Fail(BagError::Kind::kNoDepthStream, "several depth image topics (" + list.substr(1) +
                                               "): choose one with --topic");
    }
    if (named.empty())
      Fail(BagError::Kind::kNoDepthStream,
           "no depth image topic (no sensor_msgs/msg/Image topic named like depth; give "
           "--topic)");
    depth = named.front();
    r2_.depth_topic_why = "the only depth image topic";
  }
  depth_ = static_cast<std::size_t>(depth);
  depth_set_ = {depth_};
  r2_.depth_topic = topics[depth_].name;
  const std::string ns = Parent(r2_.depth_topic);
  info_topic_ = find(ns + "/camera_info");
  if (info_topic_ >= 0 && topics[info_topic_].type != ros2::kCameraInfoType) info_topic_ = -1;
  if (info_topic_ >= 0) r2_.camera_info_topic = topics[info_topic_].name;
  for (std::size_t i = 0; i < topics.size(); ++i)
    if (topics[i].type == ros2::kParameterEventType && param_topic_ < 0) {
      param_topic_ = static_cast<int>(i);
      r2_.parameter_topic = topics[i].name;
    }
}

// The first depth image (its size and encoding), the first camera_info, and the wrapper's
// depth_module parameters from the parameter events (the last value of each before the end of
// the header pass: the recording's first camera_info, or the first parameters found).
void Rosbag2Source::ReadSettings() {
  std::set<std::size_t> wanted = depth_set_;
  if (info_topic_ >= 0) wanted.insert(static_cast<std::size_t>(info_topic_));
  if (param_topic_ >= 0) wanted.insert(static_cast<std::size_t>(param_topic_));
  bool have_image = false, have_info = info_topic_ < 0, have_params = param_topic_ < 0;
  Ros2Message m;
  while (!(have_image && have_info && have_params) && storage_->Next(wanted, &m)) {
    std::string why;
    if (m.topic == depth_ && !have_image) {
      ros2::Image image;
      if (!ros2::DecodeImage(m.data, m.size, &image, &why))
        Fail(BagError::Kind::kCorrupt, r2_.depth_topic + ": " + why);
      info_.depth.encoding = image.encoding;
      info_.depth.width = static_cast<int>(std::min<std::uint32_t>(image.width, 1u << 30));
      info_.depth.height = static_cast<int>(std::min<std::uint32_t>(image.height, 1u << 30));
      if (!ros2::IsDepthEncoding(image.encoding))
        Fail(BagError::Kind::kBadEncoding, r2_.depth_topic + ": encoding '" +
                                               image.encoding.substr(0, 32) +
                                               "' (16UC1, mono16 or 32FC1 expected)");
      have_image = true;
      wanted.erase(depth_);
    } else if (static_cast<int>(m.topic) == info_topic_ && !have_info) {
      ros2::CameraInfo ci;
      if (!ros2::DecodeCameraInfo(m.data, m.size, &ci, &why) ||
          !ros2::CameraInfoToIntrinsics(ci, &info_.depth_intrinsics, &why))
        Fail(BagError::Kind::kCorrupt, r2_.camera_info_topic + ": " + why);
      info_.has_depth_intrinsics = true;
      have_info = true;
      wanted.erase(m.topic);
    } else if (static_cast<int>(m.topic) == param_topic_) {
      std::string node;
      std::vector<ros2::Parameter> params;
      if (!ros2::DecodeParameterEvent(m.data, m.size, &node, &params, &why))
        Fail(BagError::Kind::kCorrupt, r2_.parameter_topic + ": " + why);
      for (const ros2::Parameter& p : params) {
        const double value = p.type == 2 ? static_cast<double>(p.integer_value)
                             : p.type == 3 ? p.double_value
                             : p.type == 1 ? (p.bool_value ? 1.0 : 0.0)
                                           : -1.0;
        if (value < 0) continue;
        if (EndsWith(p.name, ".visual_preset")) info_.options["Visual_Preset"] = value;
        if (EndsWith(p.name, ".emitter_enabled")) info_.options["Emitter_Enabled"] = value;
        if (EndsWith(p.name, ".laser_power")) info_.options["Laser_Power"] = value;
      }
      have_params = have_params || (info_.options.count("Visual_Preset") &&
                                    info_.options.count("Emitter_Enabled"));
    }
  }
  storage_->Rewind();
  if (info_.options.count("Visual_Preset") || info_.options.count("Emitter_Enabled"))
    settings_ = "parameter messages";
}

void Rosbag2Source::Open() {
  OpenStorage();
  ChooseTopics();
  info_.file = path_;
  info_.compressed = r2_.compression.find_first_not_of("none, ") != std::string::npos;
  info_.indexed = storage_->indexed();
  for (const Ros2Topic& t : r2_.topics) {
    StreamInfo s;
    s.topic = t.name;
    s.stream_type = t.type;
    s.messages = t.messages;
    info_.streams.push_back(s);
  }
  info_.depth = info_.streams[depth_];
  info_.depth_units_m = ros2::kDepthUnitsM;
  info_.depth_frames = r2_.topics[depth_].messages;
  if (info_.depth_frames == 0) Fail(BagError::Kind::kNoDepthStream,
                                    r2_.depth_topic + " holds no message");
  ReadSettings();
  const camera::Intrinsics& in = info_.depth_intrinsics;
  if (info_.has_depth_intrinsics &&
      (in.width != info_.depth.width || in.height != info_.depth.height))
    Fail(BagError::Kind::kCorrupt, r2_.camera_info_topic + " is " + std::to_string(in.width) +
                                       "x" + std::to_string(in.height) + " px, the depth images " +
                                       std::to_string(info_.depth.width) + "x" +
                                       std::to_string(info_.depth.height) + " px");
  info_.first_timestamp_ms = r2_.start_ns / 1e6;
  info_.last_timestamp_ms = r2_.end_ns / 1e6;
  info_.device["Name"] = "RealSense (ROS 2 wrapper)";
  if (!info_.has_depth_intrinsics)
    r2_.missing.push_back("camera_info for " + r2_.depth_topic + " (no depth intrinsics)");
  if (settings_.empty())
    r2_.missing.push_back("preset and emitter (no " + std::string(ros2::kParameterEventType) +
                          " with depth_module parameters): give the manifest's preset and "
                          "emitter columns (panel_extract), or --preset and --emitter "
                          "(obstacle_detector)");
}

}  // namespace

std::unique_ptr<RecordingSource> OpenRosbag2(const std::string& path, RecordingFormat format,
                                             const RecordingOptions& options) {
  return std::make_unique<Rosbag2Source>(path, format, options);
}

const Rosbag2Info* Rosbag2InfoOf(const RecordingSource& source) {
  const auto* r = dynamic_cast<const Rosbag2Source*>(&source);
  return r ? &r->r2() : nullptr;
}

}  // namespace depthbias::io
