// The files of a split rosbag2 recording (metadata.yaml's relative_file_paths) read as one:
// topics merged by name, messages file after file.

#include <algorithm>
#include <map>

#include "io/rosbag2_storage.h"

namespace depthbias::io {
namespace {

class ChainStorage : public Ros2Storage {
 public:
  explicit ChainStorage(std::vector<std::unique_ptr<Ros2Storage>> parts)
      : parts_(std::move(parts)) {
    std::map<std::string, std::size_t> by_name;
    for (std::size_t p = 0; p < parts_.size(); ++p) {
      const std::vector<Ros2Topic>& topics = parts_[p]->topics();
      map_.emplace_back(topics.size());
      for (std::size_t i = 0; i < topics.size(); ++i) {
        auto it = by_name.find(topics[i].name);
        if (it == by_name.end()) {
          it = by_name.emplace(topics[i].name, topics_.size()).first;
          topics_.push_back(topics[i]);
          topics_.back().messages = 0;
        }
        topics_[it->second].messages += topics[i].messages;
        map_[p][i] = it->second;
      }
      const std::string c = parts_[p]->compression();
      if (compression_.find(c) == std::string::npos)
        compression_ += (compression_.empty() ? "" : ", ") + c;
    }
  }

  const std::vector<Ros2Topic>& topics() const override { return topics_; }
  bool Next(const std::set<std::size_t>& wanted, Ros2Message* msg) override {
    for (; part_ < parts_.size(); ++part_) {
      std::set<std::size_t> local;
      for (std::size_t i = 0; i < map_[part_].size(); ++i)
        if (wanted.count(map_[part_][i])) local.insert(i);
      if (!local.empty() && parts_[part_]->Next(local, msg)) {
        msg->topic = map_[part_][msg->topic];
        return true;
      }
    }
    return false;
  }
  void Rewind() override {
    for (auto& p : parts_) p->Rewind();
    part_ = 0;
  }
  std::string storage() const override { return parts_.front()->storage(); }
  std::string compression() const override { return compression_; }
  std::string damage() const override {
    for (const auto& p : parts_)
      if (!p->damage().empty()) return p->damage();
    return "";
  }
  bool indexed() const override {
    return std::all_of(parts_.begin(), parts_.end(), [](const auto& p) { return p->indexed(); });
  }
  std::int64_t start_ns() const override {
    std::int64_t t = parts_.front()->start_ns();
    for (const auto& p : parts_) t = std::min(t, p->start_ns());
    return t;
  }
  std::int64_t end_ns() const override {
    std::int64_t t = parts_.front()->end_ns();
    for (const auto& p : parts_) t = std::max(t, p->end_ns());
    return t;
  }

 private:
  std::vector<std::unique_ptr<Ros2Storage>> parts_;
  std::vector<std::vector<std::size_t>> map_;  // part's topic index → merged index
  std::vector<Ros2Topic> topics_;
  std::string compression_;
  std::size_t part_ = 0;
};

}  // namespace

std::unique_ptr<Ros2Storage> ChainStorages(std::vector<std::unique_ptr<Ros2Storage>> parts) {
  if (parts.size() == 1) return std::move(parts.front());
  return std::make_unique<ChainStorage>(std::move(parts));
}

}  // namespace depthbias::io
