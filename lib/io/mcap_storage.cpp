// Ros2Storage over an MCAP file: a topic per channel topic name, its type the channel's schema
// name; channels of one topic (several publishers) merged.

#include <algorithm>
#include <map>

#include "io/mcap_file.h"
#include "io/rosbag2_storage.h"

namespace depthbias::io {
namespace {

class McapStorage : public Ros2Storage {
 public:
  explicit McapStorage(const std::string& path) : file_(path) {
    const McapContents& c = file_.contents();
    std::map<std::string, std::size_t> by_name;
    for (const auto& kv : c.channels) {
      const mcap::Channel& ch = kv.second;
      auto it = by_name.find(ch.topic);
      if (it == by_name.end()) {
        Ros2Topic t;
        t.name = ch.topic;
        const auto s = c.schemas.find(ch.schema_id);
        t.type = s == c.schemas.end() ? "" : s->second.name;
        t.serialization_format = ch.message_encoding;
        it = by_name.emplace(ch.topic, topics_.size()).first;
        topics_.push_back(t);
      }
      const auto n = c.message_counts.find(ch.id);
      if (n != c.message_counts.end()) topics_[it->second].messages += n->second;
      topic_of_[ch.id] = it->second;
    }
    for (const std::string& s : c.compressions)
      compression_ += (compression_.empty() ? "" : ", ") + s;
  }

  const std::vector<Ros2Topic>& topics() const override { return topics_; }
  bool Next(const std::set<std::size_t>& wanted, Ros2Message* msg) override {
    if (wanted != wanted_) {
      wanted_ = wanted;
      channels_.clear();
      for (const auto& kv : topic_of_)
        if (wanted.count(kv.second)) channels_.insert(kv.first);
    }
    mcap::Message m;
    if (!file_.Next(channels_, &m)) return false;
    msg->topic = topic_of_.at(m.channel_id);
    msg->time_ns = static_cast<std::int64_t>(m.log_time_ns);
    msg->data = m.data;
    msg->size = m.size;
    return true;
  }
  void Rewind() override { file_.Rewind(); }
  std::string storage() const override { return "mcap"; }
  std::string compression() const override { return compression_; }
  std::string damage() const override { return file_.contents().damage; }
  bool indexed() const override { return file_.contents().summary; }
  std::int64_t start_ns() const override {
    return static_cast<std::int64_t>(file_.contents().message_start_ns);
  }
  std::int64_t end_ns() const override {
    return static_cast<std::int64_t>(file_.contents().message_end_ns);
  }

 private:
  McapFile file_;
  std::vector<Ros2Topic> topics_;
  std::map<std::uint16_t, std::size_t> topic_of_;
  std::set<std::size_t> wanted_;
  std::set<std::uint16_t> channels_;
  std::string compression_;
};

}  // namespace

std::unique_ptr<Ros2Storage> OpenMcapStorage(const std::string& path) {
  return std::make_unique<McapStorage>(path);
}

}  // namespace depthbias::io
