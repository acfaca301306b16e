#pragma once
// Private to io. BagReader::Impl, the state of one bag being read, and what its three source
// files share: bag_reader.cpp opens the bag and holds what both paths share (metadata, BagInfo,
// decoding a depth frame), bag_reader_rosbag.cpp the rosbag path, and bag_reader_records.cpp
// the reads of the file's records without rosbag (the structural check and the partial path).

#include <rosbag/view.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "io/bag.h"
#include "io/bag_records.h"
#include "io/rosbag_guard.h"

namespace depthbias::io {
namespace bag_detail {

constexpr std::uint64_t kMaxChunkBytes = 1ull << 28;  // larger means a damaged size field

inline std::string OneLine(std::string s) {
  std::replace(s.begin(), s.end(), '\n', ' ');
  std::replace(s.begin(), s.end(), '\r', ' ');
  return s;
}

inline std::string At(std::uint64_t offset) { return "byte " + std::to_string(offset); }

}  // namespace bag_detail

struct BagReader::Impl {
  struct Connection {
    std::string topic;
    bag_detail::TopicParts parts;
    std::uint64_t messages = 0;
  };
  struct Message {
    std::uint32_t conn = 0;
    const std::uint8_t* data = nullptr;
    std::size_t size = 0;
  };
  // Partial path: position in the file and the decompressed chunk being read.
  struct Cursor {
    std::uint64_t next_record = 0;
    std::uint64_t chunk_pos = 0;
    std::vector<std::uint8_t> raw;
    std::vector<std::uint8_t> data;
    std::size_t size = 0;
    std::size_t pos = 0;
    bool loaded = false;
    bool cut = false;  // the chunk is cut short by the end of the file
  };
  struct ChunkHead {
    std::string compression;
    std::uint32_t plain_size = 0;
    std::uint64_t data_offset = 0;
    std::uint32_t data_size = 0;
  };
  using StreamKey = std::tuple<int, std::string, int>;  // sensor, type, index

  std::string path;
  ReadOptions options;
  int fd = -1;
  std::uint64_t file_size = 0;
  std::uint64_t first_record = 0;
  BagInfo info;
  std::map<std::uint32_t, Connection> conns;
  bool has_depth = false;
  std::uint32_t depth_conn = 0;
  double fallback_units_m = 0.001;
  bool first_frame_has_units = false;
  std::string damage;
  bool finished = false;
  std::vector<std::uint8_t> bytes;  // serialized message being decoded

  // rosbag path.
  std::unique_ptr<bag_detail::GuardedBag> bag;
  std::unique_ptr<rosbag::View> frames;
  rosbag::View::iterator next_frame;
  std::uint64_t frames_read = 0;

  // Partial path.
  bool partial = false;
  Cursor cursor;

  // Recorded metadata, gathered before the first depth frame.
  std::map<int, std::map<std::string, std::string>> device_info;
  std::map<int, std::map<std::string, std::string>> sensor_info;
  std::map<int, std::map<std::string, double>> sensor_options;
  std::map<int, std::map<std::string, std::string>> option_descriptions;
  std::map<StreamKey, bag_detail::StreamInfoView> stream_infos;
  std::map<StreamKey, bag_detail::CameraInfoView> camera_infos;

  ~Impl();

  [[noreturn]] void Fail(BagError::Kind kind, const std::string& what) const {
    throw BagError(kind, path, what);
  }

  // bag_reader.cpp: opening, and what both paths share.
  void Open();
  static bool IsDepthImage(const bag_detail::TopicParts& t);
  static bool IsMetadata(const std::string& topic, const bag_detail::TopicParts& t);
  void ChooseDepth();
  void ProcessMetadata(const std::string& topic, const bag_detail::TopicParts& t,
                       const std::uint8_t* data, std::size_t size);
  void FirstFrame(const std::uint8_t* data, std::size_t size);
  void BuildInfo(bool first_seen);
  double CheckedUnits(const bag_detail::ImageView& v) const;
  void DecodeDepth(const std::uint8_t* data, std::size_t size, const std::string& where,
                   records::DepthFrame* frame) const;

  // bag_reader_records.cpp: the file's records read without rosbag.
  void ReadAt(std::uint64_t offset, std::size_t count, std::uint8_t* dst) const;
  bag_detail::RecordHeader ReadRecordHeader(std::uint64_t offset, std::uint64_t* data_offset,
                                            std::uint32_t* data_size) const;
  ChunkHead CheckChunk(std::uint64_t offset, const bag_detail::RecordHeader& h,
                       std::uint64_t data_offset, std::uint32_t data_size, bool allow_cut) const;
  void CheckStructure(std::uint64_t index_pos, std::uint32_t conn_count, std::uint32_t chunk_count);
  void CheckMessageRecord(std::uint64_t chunk_pos, const ChunkHead& chunk, std::uint32_t in_chunk,
                          std::uint32_t conn) const;
  void ReadIndex(std::uint64_t index_pos, std::uint32_t conn_count, std::uint32_t chunk_count,
                 std::set<std::uint32_t>* index_conns,
                 std::map<std::uint64_t, std::map<std::uint32_t, std::uint32_t>>* chunk_counts);
  void WalkRecords() const;
  void OpenPartial();
  bool LoadNextChunk(Cursor* c);
  bool NextInChunk(Cursor* c, Message* m);
  bool NextMessage(Cursor* c, Message* m);
  void Scan();
  bool NextPartial(records::DepthFrame* frame);

  // bag_reader_rosbag.cpp: the rosbag path.
  void ReadMessage(const rosbag::MessageInstance& m);
  void OpenWithRosbag();
  bool NextWithRosbag(records::DepthFrame* frame);
};

}  // namespace depthbias::io
