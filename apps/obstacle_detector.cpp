// obstacle_detector: obstacles in a RealSense recording, with ranges corrected by the fitted bias
// model, their σ, safe ranges and zones, one JSON line per frame (DESIGN.md "Detections JSONL").
//   obstacle_detector --weights W.yaml [--light daylight|sunset] [--k 2]
//                     [--config config/obstacle_detector.yaml] --out detections.jsonl BAG
// The scenario's preset and emitter come from the bag's recorded options, the light from --light.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "args.h"
#include "memory.h"
#include "camera/presets.h"
#include "detect/config_yaml.h"
#include "detect/detector.h"
#include "detect/json.h"
#include "io/atomic_file.h"
#include "io/recording.h"
#include "io/weights_yaml.h"
#include "model/bias_model.h"

namespace {

using namespace depthbias;

constexpr char kUsage[] =
    "usage: obstacle_detector --weights W.yaml [--light daylight|sunset] [--k 2]\n"
    "                         [--config config/obstacle_detector.yaml] --out detections.jsonl BAG\n"
    "Finds obstacles in every depth frame (voxel grid, RANSAC ground, Euclidean clusters) and\n"
    "writes one JSON line per frame: raw and corrected range, sigma, safe range (corrected\n"
    "minus k sigma) and zone of each. Preset and emitter come from the bag's options.\n";

struct Fail : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace

int main(int argc, char** argv) {
  apps::KeepLargeBlocksForReuse();
  std::string weights_path, light = "daylight", config_path, out, bag;
  double k = -1.0;
  try {
    for (apps::Args args(argc, argv); args.Next();) {
      const std::string& a = args.flag();
      if (args.IsHelp()) return apps::PrintHelp(kUsage);
      if (a == "--weights") weights_path = args.Value();
      else if (a == "--light") light = args.Value();
      else if (a == "--k") k = args.Number(false, 0);
      else if (a == "--config") config_path = args.Value();
      else if (a == "--out") out = args.Value();
      else if (a.rfind("--", 0) == 0)
        throw Fail("unknown argument '" + a + "' (see obstacle_detector --help)");
      else if (bag.empty()) bag = a;
      else throw Fail("one recording only ('" + bag + "', then '" + a + "')");
    }
    if (weights_path.empty() || out.empty() || bag.empty())
      throw Fail("usage: obstacle_detector --weights W.yaml --out detections.jsonl BAG");
    io::CheckOutputs({out}, {weights_path, config_path, bag});

    detect::DetectorParams params;
    std::string why;
    if (!config_path.empty() &&
        !detect::ParseDetectorYaml(io::ReadFile(config_path), &params, &why))
      throw Fail(config_path + ": " + why);
    if (k >= 0) params.k = k;

    const model::BiasModel bias_model(io::ReadWeightsYaml(weights_path));
    const std::unique_ptr<io::RecordingSource> recording = io::OpenRecording(bag);
    io::RecordingSource& reader = *recording;
    const io::BagInfo& info = reader.info();
    if (!info.has_depth_intrinsics) throw Fail(bag + ": no camera_info for the depth stream");
    const auto option = [&](const char* name) {
      const auto it = info.options.find(name);
      if (it == info.options.end())
        throw Fail(bag + ": no recorded option " + name + " (the scenario's preset and emitter)");
      return it->second;
    };
    const std::string preset = camera::PresetName(option("Visual_Preset"));
    const std::string emitter = option("Emitter_Enabled") != 0 ? "on" : "off";
    const auto b = info.options.find("Stereo_Baseline");
    if (b != info.options.end() && b->second > 0)
      params.baseline_m = b->second / 1000.0;  // recorded in millimetres
    const model::ScenarioModel* scenario = nullptr;
    try {
      scenario = &bias_model.Scenario(light, preset, emitter);
    } catch (const std::out_of_range& e) {
      throw Fail(weights_path + ": " + e.what());
    }
    if (!scenario->has_margin())
      throw Fail(weights_path + ": schema " + bias_model.weights().schema +
                 " holds no range-dependent margin (one sigma at every range); "
                 "refit with fit_bias");

    detect::ObstacleDetector detector(info.depth_intrinsics, params, *scenario);
    const auto start = std::chrono::steady_clock::now();
    std::string lines;
    records::DepthFrame frame;
    std::uint64_t n = 0, obstacles = 0;
    for (; reader.Next(&frame); ++n) {
      const detect::FrameDetections d = detector.Detect(frame, n);
      if (!d.success) throw Fail(bag + ": frame " + std::to_string(n) + ": " + d.message);
      obstacles += d.obstacles.size();
      lines += detect::FormatJsonLine(d);
    }
    io::WriteFileAtomic(out, lines);
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("obstacle_detector: %llu frames, %llu obstacles (%s/%s/emitter %s, k %g, "
                "stopping distance %.2f m), %.1f frames/s -> %s\n",
                static_cast<unsigned long long>(n), static_cast<unsigned long long>(obstacles),
                light.c_str(), preset.c_str(), emitter.c_str(), params.k,
                params.zones.StoppingDistanceM(), s > 0 ? n / s : 0.0, out.c_str());
  } catch (const std::exception& e) {
    std::cerr << "obstacle_detector: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
