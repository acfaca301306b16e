// Ros2Storage over a rosbag2 SQLite3 file (.db3) through Debian's libsqlite3: the tables rosbag2
// writes, topics(id, name, type, serialization_format, offered_qos_profiles, ...) and
// messages(id, topic_id, timestamp, data), opened read-only. Messages in insertion order (rowid:
// the order rosbag2 wrote them).

#include <sqlite3.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <map>

#include "io/bag.h"
#include "io/rosbag2_storage.h"

namespace depthbias::io {
namespace {

class SqliteStorage : public Ros2Storage {
 public:
  explicit SqliteStorage(const std::string& path) : path_(path) {
    try {
      Open();
    } catch (...) {
      if (db_) sqlite3_close(db_);
      throw;
    }
  }
  ~SqliteStorage() override {
    if (stmt_) sqlite3_finalize(stmt_);
    if (db_) sqlite3_close(db_);
  }

  void Open() {
    const std::string& path = path_;
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0)
      Fail(errno == ENOENT ? BagError::Kind::kNotFound : BagError::Kind::kNotAFile,
           std::strerror(errno));
    if (!S_ISREG(st.st_mode)) Fail(BagError::Kind::kNotAFile, "not a regular file");
    if (st.st_size == 0) Fail(BagError::Kind::kEmpty, "empty file");
    char head[16] = {};
    std::ifstream in(path, std::ios::binary);
    in.read(head, sizeof head);
    if (!in || std::memcmp(head, "SQLite format 3", 16) != 0)
      Fail(BagError::Kind::kNotABag, "not an SQLite3 file (no SQLite header)");
    if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX,
                        nullptr) != SQLITE_OK)
      Fail(BagError::Kind::kNotABag, std::string("sqlite: ") + sqlite3_errmsg(db_));
    sqlite3_exec(db_, "PRAGMA query_only = 1", nullptr, nullptr, nullptr);
    std::map<std::int64_t, std::size_t> index;
    sqlite3_stmt* s =
        Prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id");
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
      Ros2Topic t;
      t.name = Text(s, 1);
      t.type = Text(s, 2);
      t.serialization_format = Text(s, 3);
      index[sqlite3_column_int64(s, 0)] = topics_.size();
      topics_.push_back(t);
    }
    Finish(s, rc, "reading its topics");
    s = Prepare("SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages "
                "GROUP BY topic_id");
    bool first = true;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
      const auto it = index.find(sqlite3_column_int64(s, 0));
      if (it == index.end()) continue;  // messages of no listed topic are never read
      topics_[it->second].messages = static_cast<std::uint64_t>(sqlite3_column_int64(s, 1));
      const std::int64_t a = sqlite3_column_int64(s, 2), b = sqlite3_column_int64(s, 3);
      start_ns_ = first ? a : std::min(start_ns_, a);
      end_ns_ = first ? b : std::max(end_ns_, b);
      first = false;
    }
    Finish(s, rc, "counting its messages");
    for (const auto& kv : index) ids_[kv.second] = kv.first;
  }

  const std::vector<Ros2Topic>& topics() const override { return topics_; }
  bool Next(const std::set<std::size_t>& wanted, Ros2Message* msg) override {
    if (!stmt_ || wanted != wanted_) {
      if (stmt_) sqlite3_finalize(stmt_);
      stmt_ = nullptr;
      wanted_ = wanted;
      std::string list;
      for (std::size_t t : wanted)
        if (ids_.count(t)) list += (list.empty() ? "" : ",") + std::to_string(ids_[t]);
      if (list.empty()) return false;
      stmt_ = Prepare("SELECT topic_id, timestamp, data FROM messages WHERE topic_id IN (" +
                      list + ") ORDER BY id");
    }
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_DONE) return false;
    if (rc != SQLITE_ROW) Fail(BagError::Kind::kCorrupt,
                               std::string("sqlite: reading its messages: ") + sqlite3_errmsg(db_));
    const std::int64_t id = sqlite3_column_int64(stmt_, 0);
    for (const auto& kv : ids_)
      if (kv.second == id) msg->topic = kv.first;
    msg->time_ns = sqlite3_column_int64(stmt_, 1);
    msg->data = static_cast<const std::uint8_t*>(sqlite3_column_blob(stmt_, 2));
    msg->size = static_cast<std::size_t>(sqlite3_column_bytes(stmt_, 2));
    return true;
  }
  void Rewind() override {
    if (stmt_) sqlite3_reset(stmt_);
  }
  std::string storage() const override { return "sqlite3"; }
  std::string compression() const override { return "none"; }
  std::int64_t start_ns() const override { return start_ns_; }
  std::int64_t end_ns() const override { return end_ns_; }

 private:
  [[noreturn]] void Fail(BagError::Kind kind, const std::string& what) {
    throw BagError(kind, path_, what);
  }
  sqlite3_stmt* Prepare(const std::string& sql) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &s, nullptr) != SQLITE_OK) {
      const std::string why = sqlite3_errmsg(db_);
      sqlite3_finalize(s);
      Fail(why.find("no such") != std::string::npos ? BagError::Kind::kNotABag
                                                     : BagError::Kind::kCorrupt,
           "not a rosbag2 SQLite3 file (sqlite: " + why + ")");
    }
    return s;
  }
  void Finish(sqlite3_stmt* s, int rc, const char* what) {
    sqlite3_finalize(s);
    if (rc != SQLITE_DONE)
      Fail(BagError::Kind::kCorrupt, std::string("sqlite: ") + what + ": " + sqlite3_errmsg(db_));
  }
  static std::string Text(sqlite3_stmt* s, int col) {
    const unsigned char* t = sqlite3_column_text(s, col);
    return t ? reinterpret_cast<const char*>(t) : "";
  }

  std::string path_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* stmt_ = nullptr;
  std::vector<Ros2Topic> topics_;
  std::map<std::size_t, std::int64_t> ids_;  // topic index → topics.id
  std::set<std::size_t> wanted_;
  std::int64_t start_ns_ = 0, end_ns_ = 0;
};

}  // namespace

std::unique_ptr<Ros2Storage> OpenSqliteStorage(const std::string& path) {
  return std::make_unique<SqliteStorage>(path);
}

}  // namespace depthbias::io
