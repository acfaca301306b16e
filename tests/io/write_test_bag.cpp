// write_test_bag OUT_DIR: writes bags with depthbias::io::BagWriter for scripts/check_playback.py
// to play back with librealsense. Pixels follow TestPixel() below (the script computes the same);
// OUT_DIR/written.json lists each bag's intrinsics, depth units, options, device info, frame
// numbers and timestamps.

#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>

#include "io/bag.h"
#include "io/bag_summary.h"

namespace {

// The same formula is in scripts/check_playback.py.
std::uint16_t TestPixel(int u, int v, int i) {
  if ((u + 2 * v + i) % 13 == 0) return 0;
  return static_cast<std::uint16_t>((7 * u + 131 * v + 1009 * i) % 65535 + 1);
}

struct Spec {
  std::string name;
  bool lz4;
  int width, height, frames;
  double units_m;
  double preset, emitter, laser_mw;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: write_test_bag OUT_DIR\n";
    return 2;
  }
  const std::string dir = argv[1];
  const Spec specs[] = {
      {"written_plain", false, 64, 48, 5, 0.001, 3, 1, 150},
      {"written_lz4", true, 64, 48, 5, 0.0001, 4, 0, 0},
      {"written_chunks", false, 320, 240, 9, 0.001, 3, 1, 360},  // several chunks
  };
  std::string json = "[";
  for (const Spec& s : specs) {
    depthbias::io::BagWriterConfig c;
    c.intrinsics.width = s.width;
    c.intrinsics.height = s.height;
    c.intrinsics.fx = 0.625 * s.width + 0.125;
    c.intrinsics.fy = 0.625 * s.width + 0.375;
    c.intrinsics.ppx = s.width / 2.0 - 0.5;
    c.intrinsics.ppy = s.height / 2.0 + 0.25;
    c.intrinsics.model = depthbias::camera::Distortion::kBrownConrady;
    c.intrinsics.coeffs = {-0.0546875, 0.0625, -0.000244140625, 0.00048828125, -0.015625};
    c.depth_units_m = s.units_m;
    c.compress_lz4 = s.lz4;
    c.options = {{"Visual_Preset", s.preset}, {"Emitter_Enabled", s.emitter},
                 {"Laser_Power", s.laser_mw}};
    c.device = {{"Name", "Intel RealSense D455"}, {"Serial Number", "000000000042"},
                {"Firmware Version", "5.16.0.1"}};
    const std::string path = dir + "/" + s.name + ".bag";
    try {
      depthbias::io::BagWriter writer(path, c);
      for (int i = 0; i < s.frames; ++i) {
        depthbias::records::DepthFrame f;
        f.width = s.width;
        f.height = s.height;
        f.depth_units_m = s.units_m;
        f.frame_number = 7 + i;
        f.timestamp_ms = 5000.0 + 33.25 * i;
        f.counts.resize(static_cast<std::size_t>(s.width) * s.height);
        for (int v = 0; v < s.height; ++v)
          for (int u = 0; u < s.width; ++u) f.counts[v * s.width + u] = TestPixel(u, v, i);
        writer.Write(f);
      }
      writer.Close();
    } catch (const depthbias::io::BagError& e) {
      std::cerr << "write_test_bag: " << e.what() << "\n";
      return 1;
    }
    using depthbias::io::FormatNumber;
    const auto& in = c.intrinsics;
    std::string one = "{\"file\":\"" + s.name + ".bag\",\"compressed\":" +
                      (s.lz4 ? "true" : "false") + ",\"intrinsics\":{\"width\":" +
                      std::to_string(in.width) + ",\"height\":" + std::to_string(in.height) +
                      ",\"fx\":" + FormatNumber(in.fx) + ",\"fy\":" + FormatNumber(in.fy) +
                      ",\"ppx\":" + FormatNumber(in.ppx) + ",\"ppy\":" + FormatNumber(in.ppy) +
                      ",\"model\":\"Brown Conrady\",\"coeffs\":[";
    for (std::size_t k = 0; k < in.coeffs.size(); ++k)
      one += (k ? "," : "") + FormatNumber(in.coeffs[k]);
    one += "]},\"depth_units\":" + FormatNumber(s.units_m) + ",\"options\":{";
    for (const auto& [name, value] : c.options)
      one += "\"" + name + "\":" + FormatNumber(value) + ",";
    one += "\"Depth_Units\":" + FormatNumber(s.units_m) + "},\"device\":{";
    bool first = true;
    for (const auto& [key, value] : c.device) {
      one += std::string(first ? "" : ",") + "\"" + key + "\":\"" + value + "\"";
      first = false;
    }
    one += "},\"frames\":[";
    for (int i = 0; i < s.frames; ++i)
      one += std::string(i ? "," : "") + "{\"frame_number\":" + std::to_string(7 + i) +
             ",\"timestamp_ms\":" + FormatNumber(5000.0 + 33.25 * i) + "}";
    json += (json.size() > 1 ? "," : "") + one + "]}";
  }
  std::ofstream(dir + "/written.json") << json << "]\n";
  return 0;
}
