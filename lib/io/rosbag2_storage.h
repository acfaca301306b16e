#pragma once
// A rosbag2 storage file's topics and messages, whatever holds them: an MCAP file (the default
// since Iron) or an SQLite3 .db3 file (the default on Humble), and the files of a split
// recording one after another. Messages come in file order with their receive time and their
// CDR bytes.

#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace depthbias::io {

struct Ros2Topic {
  std::string name;
  std::string type;                  // e.g. sensor_msgs/msg/Image
  std::string serialization_format;  // "cdr"
  std::uint64_t messages = 0;
};

struct Ros2Message {
  std::size_t topic = 0;  // index in topics()
  std::int64_t time_ns = 0;
  const std::uint8_t* data = nullptr;  // valid until the next call of Next
  std::size_t size = 0;
};

class Ros2Storage {
 public:
  virtual ~Ros2Storage() = default;
  virtual const std::vector<Ros2Topic>& topics() const = 0;
  // Next message of a topic in wanted (indexes into topics()); false at the end. Throws
  // BagError naming the file on damage.
  virtual bool Next(const std::set<std::size_t>& wanted, Ros2Message* msg) = 0;
  virtual void Rewind() = 0;
  virtual std::string storage() const = 0;      // "mcap" or "sqlite3"
  virtual std::string compression() const = 0;  // chunk compressions ("zstd", "none", ...)
  virtual std::string damage() const { return ""; }  // where a scanned file stopped
  virtual bool indexed() const { return true; }       // summary / index used
  virtual std::int64_t start_ns() const = 0;
  virtual std::int64_t end_ns() const = 0;
};

// Throw BagError naming the file.
std::unique_ptr<Ros2Storage> OpenMcapStorage(const std::string& path);
std::unique_ptr<Ros2Storage> OpenSqliteStorage(const std::string& path);
// The files of one recording read one after another, topics merged by name (at least one).
std::unique_ptr<Ros2Storage> ChainStorages(std::vector<std::unique_ptr<Ros2Storage>> parts);

}  // namespace depthbias::io
