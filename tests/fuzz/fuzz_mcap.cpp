// libFuzzer target: any bytes as a rosbag2 MCAP file. OpenRecording must either read it (topics,
// camera_info, parameters, every depth frame) or throw BagError — never crash, hang, leak or
// allocate without bound. The bytes live in a memfd (recognized by MCAP's magic).
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <string>

#include "io/recording.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const int fd = ::memfd_create("fuzz.mcap", 0);
  if (fd < 0) return 0;
  if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, data, size, 0) != static_cast<ssize_t>(size))
    return 0;
  static const std::string path = "/proc/self/fd/" + std::to_string(fd);
  try {
    const auto source = depthbias::io::OpenRecording(path);
    const auto& info = source->info();
    if (info.has_depth_intrinsics) {
      std::string why;
      if (!info.depth_intrinsics.IsValid(&why)) __builtin_trap();  // checked on reading
    }
    depthbias::records::DepthFrame frame;
    for (int i = 0; i < 64 && source->Next(&frame); ++i) {
      if (frame.counts.size() != static_cast<std::size_t>(frame.width) * frame.height ||
          !(frame.depth_units_m > 0))
        __builtin_trap();
    }
    (void)source->SummaryText();
  } catch (const depthbias::io::BagError&) {
  }
  return 0;
}
