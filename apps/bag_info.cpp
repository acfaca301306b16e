// bag_info FILE... [--json]: what a recording holds. A RealSense ROS 1 bag: streams, depth
// intrinsics, depth units, frame count and time span, recorded options, device info. A rosbag2
// recording (folder with metadata.yaml, .mcap, .db3): what `ros2 bag info` prints, then the
// depth topic, intrinsics, preset and emitter and what is missing. Exits non-zero if any cannot
// be read; with --json, such a recording gives {"file": ..., "error": ...}.
// --read-all also decodes every depth frame and reports the read rate (for benchmarks);
// --partial reads a damaged bag up to the damage.

#include <chrono>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include "args.h"
#include "io/bag.h"
#include "io/bag_summary.h"
#include "io/recording.h"

namespace {

void Usage(std::ostream& out) {
  out << "usage: bag_info RECORDING... [--json] [--read-all] [--partial] [--topic T]\n"
         "What a recording holds: a RealSense ROS 1 .bag, or a rosbag2 folder (metadata.yaml),\n"
         ".mcap or .db3. Options (default: all off):\n"
         "  --topic T   the depth topic of a ROS 2 recording (found by type and name)\n"
         "  --json      one JSON object per bag, one per line\n"
         "  --partial   read a damaged bag up to the damage\n"
         "  --read-all  decode every depth frame and print frames/s\n"
      << depthbias::apps::kExitHelp;
}

}  // namespace

int main(int argc, char** argv) {
  depthbias::io::PrepareRosEnvironment();
  bool json = false, read_all = false, partial = false;
  std::string topic;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--json") {
      json = true;
    } else if (a == "--read-all") {
      read_all = true;
    } else if (a == "--partial") {
      partial = true;
    } else if (a == "--topic") {
      if (i + 1 == argc) {
        std::cerr << "bag_info: --topic needs a topic name (see bag_info --help)\n";
        return depthbias::apps::kExitError;
      }
      topic = argv[++i];
    } else if (a == "-h" || a == "--help") {
      Usage(std::cout);
      return 0;
    } else if (a.size() > 1 && a[0] == '-') {
      std::cerr << "bag_info: unknown option " << a << " (see bag_info --help)\n";
      return depthbias::apps::kExitError;
    } else {
      files.push_back(a);
    }
  }
  if (files.empty()) {
    std::cerr << "bag_info: no FILE given (see bag_info --help)\n";
    return depthbias::apps::kExitError;
  }
  std::size_t failures = 0;
  for (const std::string& file : files) {
    try {
      const auto start = std::chrono::steady_clock::now();
      const auto reader = depthbias::io::OpenRecording(file, {topic, partial});
      std::uint64_t frames = 0, checksum = 0;
      if (read_all) {
        depthbias::records::DepthFrame frame;
        while (reader->Next(&frame)) {
          ++frames;
          checksum += frame.counts[frame.counts.size() / 2];
        }
      }
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (json) {
        std::string out = reader->SummaryJson();
        if (read_all) {
          out.pop_back();
          out += ",\"read_all\":{\"frames\":" + std::to_string(frames) +
                 ",\"seconds\":" + depthbias::io::FormatNumber(seconds) +
                 ",\"checksum\":" + std::to_string(checksum) + "}}";
        }
        std::cout << out << "\n";
      } else {
        std::cout << reader->SummaryText();
        if (reader->format_name() == "ROS 1 bag" && !reader->damage().empty())
          std::cout << "damage:      " << reader->damage() << "\n";
        if (read_all)
          std::printf("read-all:    %llu frames in %.3f s = %.1f frames/s (checksum %llu)\n",
                      static_cast<unsigned long long>(frames), seconds,
                      seconds > 0 ? frames / seconds : 0.0,
                      static_cast<unsigned long long>(checksum));
        if (files.size() > 1) std::cout << "\n";
      }
    } catch (const std::exception& e) {
      ++failures;
      const std::string what = dynamic_cast<const depthbias::io::BagError*>(&e)
                                   ? e.what()
                                   : file + ": " + (dynamic_cast<const std::bad_alloc*>(&e)
                                                        ? "out of memory while reading it"
                                                        : e.what());
      if (json) {
        std::cout << depthbias::io::BagErrorJson(file, what) << "\n";
      } else {
        std::cerr << "bag_info: " << what << "\n";
      }
    }
  }
  std::cout.flush();
  if (files.size() > 1)
    std::cerr << "bag_info: "
              << depthbias::apps::Summary(files.size(), "bag",
                                          {{"ok", files.size() - failures}, {"unreadable", failures}},
                                          "")
              << "\n";
  return failures == 0 ? depthbias::apps::kExitOk : depthbias::apps::kExitRowsFailed;
}
