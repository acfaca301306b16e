// The rosbag path of BagReader (bag_reader.cpp says how the reader works): a bag that passed the
// structural check is opened with rosbag::Bag; one rosbag::View gives its metadata and one its
// depth frames, decoded from their serialized bytes.

#include <console_bridge/console.h>
#include <ros/exception.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "io/bag.h"
#include "io/bag_reader_impl.h"
#include "io/bag_records.h"
#include "io/rosbag_guard.h"

namespace depthbias::io {
namespace {

using namespace bag_detail;

// rosbag::MessageInstance::write() target: the serialized bytes of one message, in a buffer
// reused from message to message.
struct ByteSink {
  std::vector<std::uint8_t>* bytes;
  std::uint8_t* advance(std::uint32_t n) {
    if (n > kMaxChunkBytes) throw FormatError("message of " + std::to_string(n) + " bytes");
    bytes->resize(n);
    return bytes->data();
  }
};

// A depth image as rosbag's MessageInstance::instantiate() sees it: instead of building a
// sensor_msgs::Image (a copy of the pixels), its deserializer hands the serialized bytes, in
// place in rosbag's chunk buffer, to the decoder of the frame being read.
struct DepthImageBytes {};

struct DepthDecoder {
  virtual void Decode(const std::uint8_t* data, std::size_t size) = 0;
  virtual ~DepthDecoder() = default;
};
thread_local DepthDecoder* tl_depth_decoder = nullptr;

}  // namespace
}  // namespace depthbias::io

namespace ros {
namespace message_traits {
template <>
struct MD5Sum<depthbias::io::DepthImageBytes> {
  static const char* value() { return MD5Sum<sensor_msgs::Image>::value(); }
  static const char* value(const depthbias::io::DepthImageBytes&) { return value(); }
};
}  // namespace message_traits
namespace serialization {
template <>
struct Serializer<depthbias::io::DepthImageBytes> {
  template <typename Stream>
  static void read(Stream& stream, depthbias::io::DepthImageBytes&) {
    const std::uint32_t size = stream.getLength();
    const std::uint8_t* data = stream.advance(size);
    depthbias::io::tl_depth_decoder->Decode(data, size);
  }
};
}  // namespace serialization
}  // namespace ros

namespace depthbias::io {

// The serialized bytes of one message into `bytes`.
void BagReader::Impl::ReadMessage(const rosbag::MessageInstance& m) {
  ByteSink sink{&bytes};
  bytes.clear();
  m.write(sink);
}

void BagReader::Impl::OpenWithRosbag() {
  // rosbag and ros::Header report some errors on the console before throwing; the library
  // does not print (the exception carries the error).
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_NONE);
  bool first_seen = false;
  std::string where = "opening it with rosbag";
  try {
    bag = std::make_unique<bag_detail::GuardedBag>();
    bag->Open(path, rosbag::bagmode::Read);
    where = "reading its index with rosbag";
    rosbag::View all(**bag);
    for (const rosbag::ConnectionInfo* c : all.getConnections()) {
      Connection& conn = conns[c->id];
      conn.topic = c->topic;
      conn.parts = ParseTopic(c->topic);
    }
    for (auto& [id, conn] : conns) {
      const std::uint32_t want = id;
      rosbag::View one(**bag, [want](const rosbag::ConnectionInfo* c) { return c->id == want; });
      conn.messages = one.size();
    }
    ChooseDepth();
    ros::Time first_time = ros::TIME_MAX;
    if (has_depth) {
      const std::uint32_t want = depth_conn;
      frames = std::make_unique<rosbag::View>(
          **bag, [want](const rosbag::ConnectionInfo* c) { return c->id == want; });
      rosbag::View::iterator it = frames->begin();
      if (it != frames->end()) {
        where = "reading its first depth frame";
        first_time = it->getTime();
        ReadMessage(*it);
        FirstFrame(bytes.data(), bytes.size());
        first_seen = true;
        rosbag::View::iterator last = it;
        for (++it; it != frames->end(); ++it) last = it;
        where = "reading its last depth frame";
        ReadMessage(*last);
        std::uint32_t seq = 0;
        DecodeStamp(bytes.data(), bytes.size(), &seq, &info.last_timestamp_ms);
      }
    }
    // Device and sensor info, options, stream info and camera_info recorded up to the first
    // depth frame.
    where = "reading its recorded options and stream info";
    const auto is_metadata = [](const rosbag::ConnectionInfo* c) {
      return IsMetadata(c->topic, ParseTopic(c->topic));
    };
    rosbag::View metadata(**bag, is_metadata, ros::TIME_MIN, first_time);
    for (const rosbag::MessageInstance& m : metadata) {
      where = "reading " + m.getTopic();
      ReadMessage(m);
      ProcessMetadata(m.getTopic(), ParseTopic(m.getTopic()), bytes.data(), bytes.size());
    }
  } catch (const FormatError& e) {
    Fail(BagError::Kind::kCorrupt, where + ": " + e.what());
  } catch (const ros::Exception& e) {  // rosbag::BagException and roscpp_serialization's
    Fail(BagError::Kind::kCorrupt, where + ": " + e.what());
  } catch (const std::bad_alloc&) {
    Fail(BagError::Kind::kCorrupt, where + ": out of memory");
  }
  BuildInfo(first_seen);
  if (frames) next_frame = frames->begin();
}

bool BagReader::Impl::NextWithRosbag(records::DepthFrame* frame) {
  if (!frames || next_frame == frames->end()) return false;
  const std::string where = "depth frame " + std::to_string(frames_read + 1) + " of " +
                            std::to_string(info.depth_frames);
  struct Decoder : DepthDecoder {
    const Impl* impl;
    const std::string* where;
    records::DepthFrame* frame;
    Decoder(const Impl* i, const std::string* w, records::DepthFrame* f)
        : impl(i), where(w), frame(f) {}
    void Decode(const std::uint8_t* data, std::size_t size) override {
      impl->DecodeDepth(data, size, *where, frame);
    }
  } decoder(this, &where, frame);
  tl_depth_decoder = &decoder;
  try {
    if (!next_frame->instantiate<DepthImageBytes>())
      Fail(BagError::Kind::kCorrupt, where + ": is a " + next_frame->getDataType() +
                                         " message, not a sensor_msgs/Image");
  } catch (const ros::Exception& e) {  // rosbag::BagException and roscpp_serialization's
    tl_depth_decoder = nullptr;
    Fail(BagError::Kind::kCorrupt, where + ": " + e.what());
  } catch (...) {
    tl_depth_decoder = nullptr;
    throw;
  }
  tl_depth_decoder = nullptr;
  ++next_frame;
  ++frames_read;
  return true;
}

}  // namespace depthbias::io
