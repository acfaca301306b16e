#include "io/rosbag2_metadata.h"

#include "io/yaml_limits.h"

namespace depthbias::io {
namespace {

template <typename T>
T Get(const YAML::Node& node, const char* key, const T& fallback, const std::string& file) {
  const YAML::Node v = node[key];
  if (!v) return fallback;
  try {
    return v.as<T>();
  } catch (const YAML::Exception&) {
    throw IoError(file + ": " + key + " is not what rosbag2 writes there");
  }
}

}  // namespace

Rosbag2Metadata ParseRosbag2Metadata(const std::string& text, const std::string& file) {
  const YAML::Node doc = LoadYaml(text, file);
  const YAML::Node info = doc.IsMap() ? doc["rosbag2_bagfile_information"] : YAML::Node();
  if (!info || !info.IsMap())
    throw IoError(file + ": no rosbag2_bagfile_information (not a rosbag2 metadata.yaml)");
  Rosbag2Metadata m;
  m.version = Get<int>(info, "version", 0, file);
  m.storage_identifier = Get<std::string>(info, "storage_identifier", "", file);
  m.message_count = Get<std::uint64_t>(info, "message_count", 0, file);
  m.compression_format = Get<std::string>(info, "compression_format", "", file);
  m.compression_mode = Get<std::string>(info, "compression_mode", "", file);
  if (const YAML::Node d = info["duration"]; d && d.IsMap())
    m.duration_ns = Get<std::int64_t>(d, "nanoseconds", 0, file);
  if (const YAML::Node s = info["starting_time"]; s && s.IsMap())
    m.starting_time_ns = Get<std::int64_t>(s, "nanoseconds_since_epoch", 0, file);
  const YAML::Node paths = info["relative_file_paths"];
  if (!paths || !paths.IsSequence() || paths.size() == 0)
    throw IoError(file + ": relative_file_paths lists no storage file");
  for (const YAML::Node& p : paths) {
    if (!p.IsScalar()) throw IoError(file + ": relative_file_paths holds a non-name");
    const std::string name = p.as<std::string>();
    if (name.empty() || name.find("..") != std::string::npos || name[0] == '/')
      throw IoError(file + ": storage file '" + name.substr(0, 64) +
                    "' is not a name inside the folder");
    m.relative_file_paths.push_back(name);
  }
  if (const YAML::Node topics = info["topics_with_message_count"]; topics && topics.IsSequence()) {
    for (const YAML::Node& t : topics) {
      const YAML::Node meta = t.IsMap() ? t["topic_metadata"] : YAML::Node();
      if (!meta || !meta.IsMap()) throw IoError(file + ": a topic without topic_metadata");
      Ros2Topic topic;
      topic.name = Get<std::string>(meta, "name", "", file);
      topic.type = Get<std::string>(meta, "type", "", file);
      topic.serialization_format = Get<std::string>(meta, "serialization_format", "", file);
      topic.messages = Get<std::uint64_t>(t, "message_count", 0, file);
      m.topics.push_back(topic);
    }
  }
  return m;
}

Rosbag2Metadata ReadRosbag2Metadata(const std::string& path) {
  return ParseRosbag2Metadata(ReadYamlFile(path), path);
}

}  // namespace depthbias::io
