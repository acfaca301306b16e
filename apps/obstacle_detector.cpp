// obstacle_detector: obstacles in a RealSense recording, with ranges corrected by the fitted bias
// model, their σ, safe ranges and zones, one JSON line per frame (DESIGN.md "Detections JSONL").
//   obstacle_detector --weights W.yaml [--light daylight|sunset] [--k 2] [--safe-beyond-raw]
//                     [--config config/obstacle_detector.yaml] --out detections.jsonl BAG
// The scenario's preset and emitter come from the bag's recorded options, the light from --light.
// The margin's disparity noise σ_d: the weights' for that scenario when they hold one, else the
// recording's own frames', else the config's; the summary line and every JSON line say which.
// Exit status as every tool: 0 every frame seen, 1 written but some frames blind, 2 nothing
// written.
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
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
#include "io/temp_files.h"
#include "io/weights_yaml.h"
#include "model/bias_model.h"
#include "records/number_text.h"

namespace {

using namespace depthbias;

constexpr char kUsage[] =
    "usage: obstacle_detector --weights W.yaml [--light daylight|sunset] [--k 2]\n"
    "                         [--safe-beyond-raw] [--config config/obstacle_detector.yaml]\n"
    "                         --out detections.jsonl BAG\n"
    "Finds obstacles in every depth frame (voxel grid, RANSAC ground, Euclidean clusters) and\n"
    "writes one JSON line per frame: its status (ok, or blind when less than cloud.min_valid_pct\n"
    "of its samples hold a depth: never a clear zone) and for each obstacle the raw and corrected\n"
    "range, sigma, safe range and zone. Preset and emitter come from the recording (a ROS 1\n"
    "bag's options, a ROS 2 recording's parameter messages), else from --preset and --emitter.\n"
    "The reading noise sigma_d of the margin: the weights' for the scenario (fit_bias writes\n"
    "it from the panel recordings), else measured on the recording's first frames, else the\n"
    "config's cluster.disparity_noise_px; said in the summary and every line.\n"
    "Options (default):\n"
    "  --weights FILE     weights YAML of fit_bias (required)\n"
    "  --light L          the scenario's light (daylight)\n"
    "  --preset P         the preset (HA, HD, ...) when the recording does not hold it; one\n"
    "                     that differs from the recording's is refused (the recording's)\n"
    "  --emitter on|off   the emitter likewise (the recording's)\n"
    "  --k K              standard deviations of the margin, in (0, 10] (2, or the config's)\n"
    "  --safe-beyond-raw  safe range = corrected - k sigma even beyond the raw range (off: the\n"
    "                     safe range is min(raw, corrected - k sigma)); said in every line\n"
    "  --config FILE      detector parameters YAML (the built-in defaults)\n"
    "  --out FILE         detections JSONL (required)\n"
    "A run with a blind frame writes its output and exits 1.\n";

// --k: k standard deviations, in (0, 10]. A number too small for a double's normal range
// (1e-320) is still a number: it is read as the nearest double, never called "not finite".
double ParseK(const std::string& text) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || std::isnan(v))
    throw std::invalid_argument("--k '" + text + "' is not a number");
  if (!(v > 0.0 && v <= depthbias::detect::kMaxK))
    throw std::invalid_argument("--k '" + text + "' is outside (0, 10] (standard deviations)");
  return v;
}

struct Fail : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// σ_d of the margin: the unit's, from the weights (the median of its panel recordings' σ_d in
// this scenario), else the recording's own (the temporal spread at the obstacles of its first
// frames, lib/detect/noise.h), else the configured one. Says which.
std::string ChooseNoise(const std::string& bag, const detect::DetectorParams& params,
                        const records::BiasWeightsGroup& group, const std::string& preset,
                        detect::ObstacleDetector* detector) {
  const double weights_px = detect::WeightsDisparityNoisePx(group, preset);
  if (std::isfinite(weights_px)) {
    detector->SetDisparityNoisePx(weights_px, detect::NoiseSource::kWeights);
    return "sigma_d " + records::NumberText(weights_px) + " px from the weights (" + group.light +
           "/" + group.preset + ", median of " +
           std::to_string(group.disparity_noise.recordings) + " recordings)";
  }
  const std::string configured =
      "sigma_d " + records::NumberText(params.cluster.disparity_noise_px) + " px configured";
  if (!params.noise.from_frames) return configured;
  const std::unique_ptr<io::RecordingSource> first = io::OpenRecording(bag);
  records::DepthFrame frame;
  int n = 0;
  for (; n < params.noise.frames && first->Next(&frame); ++n) {
    if (!detector->Detect(frame, static_cast<std::uint64_t>(n)).success) break;
  }
  const double sigma_px = detector->temporal_noise().SigmaPx();
  const long long measured = detector->temporal_noise().pairs();
  const std::string pairs =
      std::to_string(measured) + " pixel pairs at obstacles in " + std::to_string(n) + " frames";
  detector->ResetTemporalNoise();
  if (measured < params.noise.min_pairs)
    return configured + " (" + pairs + ": too few to measure it)";
  if (!(sigma_px > 0.0)) return configured + " (" + pairs + ": none changed between frames)";
  detector->SetDisparityNoisePx(sigma_px, detect::NoiseSource::kRecording);
  return "sigma_d " + records::NumberText(sigma_px) + " px from the recording (" + pairs + ")";
}

int Error(const std::string& what) {
  std::cerr << "obstacle_detector: " << what << "\n";
  return apps::kExitError;
}

}  // namespace

int main(int argc, char** argv) {
  apps::KeepLargeBlocksForReuse();
  io::PrepareRosEnvironment();
  io::InstallSignalCleanup();
  std::string weights_path, light = "daylight", config_path, out, bag, given_preset,
      given_emitter;
  double k = -1.0;
  bool safe_beyond_raw = false;
  std::uint64_t n = 0, blind = 0, obstacles = 0;
  try {
    for (apps::Args args(argc, argv); args.Next();) {
      const std::string& a = args.flag();
      if (args.IsHelp()) return apps::PrintHelp(kUsage);
      if (a == "--weights") weights_path = args.Value();
      else if (a == "--light") light = args.Value();
      else if (a == "--preset") given_preset = args.Value();
      else if (a == "--emitter") given_emitter = args.Value();
      else if (a == "--k") k = ParseK(args.Value());
      else if (a == "--safe-beyond-raw") safe_beyond_raw = true;
      else if (a == "--config") config_path = args.Value();
      else if (a == "--out") out = args.Value();
      else if (a.rfind("--", 0) == 0)
        throw Fail("unknown argument '" + a + "' (see obstacle_detector --help)");
      else if (bag.empty()) bag = a;
      else throw Fail("one recording only ('" + bag + "', then '" + a + "')");
    }
    if (weights_path.empty() || out.empty() || bag.empty())
      throw Fail("usage: obstacle_detector --weights W.yaml --out detections.jsonl BAG");
    double given_preset_value = 0;
    if (!given_preset.empty() && !camera::PresetOptionValue(given_preset, &given_preset_value))
      throw Fail("--preset '" + given_preset + "' is not a D455 preset (HA, HD, ...)");
    if (!given_emitter.empty() && given_emitter != "on" && given_emitter != "off")
      throw Fail("--emitter '" + given_emitter + "' is neither on nor off");
    io::CheckOutputs({out}, {weights_path, config_path, bag});
    io::CheckOutputFile(out);

    detect::DetectorParams params;
    std::string why;
    if (!config_path.empty() &&
        !detect::ParseDetectorYaml(io::ReadFile(config_path), &params, &why))
      throw Fail(config_path + ": " + why);
    if (k > 0) params.k = k;
    if (safe_beyond_raw) params.safe_beyond_raw = true;

    // The model's own refusals (a form's constants, a group's weights) name the file too.
    const records::BiasWeights weights = io::ReadWeightsYaml(weights_path);
    std::unique_ptr<model::BiasModel> made;
    try {
      made = std::make_unique<model::BiasModel>(weights);
    } catch (const std::invalid_argument& e) {
      throw Fail(weights_path + ": " + e.what());
    }
    const model::BiasModel& bias_model = *made;
    const std::unique_ptr<io::RecordingSource> recording = io::OpenRecording(bag);
    io::RecordingSource& reader = *recording;
    const io::BagInfo& info = reader.info();
    if (!info.has_depth_intrinsics) throw Fail(bag + ": no camera_info for the depth stream");
    // The recording's word, else the user's; both given and different: refused.
    const auto setting = [&](const char* name, const char* flag, const std::string& given,
                             const std::string& recorded_text, bool recorded) {
      if (!recorded && given.empty())
        throw Fail(bag + ": no recorded " + name + " (" + reader.format_name() +
                   " without it): give " + flag);
      if (recorded && !given.empty() && given != recorded_text)
        throw Fail(bag + ": " + flag + " " + given + " differs from the recording's " + name +
                   " " + recorded_text);
      return recorded ? recorded_text : given;
    };
    const auto vp = info.options.find("Visual_Preset");
    const auto ee = info.options.find("Emitter_Enabled");
    const std::string preset =
        setting("preset (Visual_Preset)", "--preset", given_preset,
                vp != info.options.end() ? camera::PresetName(vp->second) : "",
                vp != info.options.end());
    const std::string emitter =
        setting("emitter (Emitter_Enabled)", "--emitter", given_emitter,
                ee != info.options.end() ? (ee->second != 0 ? "on" : "off") : "",
                ee != info.options.end());
    const std::string settings_from =
        vp != info.options.end() && ee != info.options.end() ? reader.settings_source()
        : vp == info.options.end() && ee == info.options.end()
            ? "--preset and --emitter"
            : reader.settings_source() + " and the command line";
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
    const std::string noise = ChooseNoise(bag, params, scenario->group(), preset, &detector);
    std::string lines;
    records::DepthFrame frame;
    for (; reader.Next(&frame); ++n) {
      const detect::FrameDetections d = detector.Detect(frame, n);
      if (!d.success) throw Fail(bag + ": frame " + std::to_string(n) + ": " + d.message);
      obstacles += d.obstacles.size();
      blind += d.blind;
      lines += detect::FormatJsonLine(d, params.safe_beyond_raw);
    }
    io::WriteFileAtomic(out, lines);
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // "20 frames: 18 ok, 2 blind; 34 obstacles (daylight/HD/emitter on, ...) → out"
    std::printf("obstacle_detector: %s; %llu obstacles (%s/%s/emitter %s from %s, k %g%s, %s, "
                "stopping distance %.2f m), %.1f frames/s \u2192 %s\n",
                apps::Summary(n, "frame", {{"ok", n - blind}, {"blind", blind}}, "").c_str(),
                static_cast<unsigned long long>(obstacles), light.c_str(), preset.c_str(),
                emitter.c_str(), settings_from.c_str(), params.k,
                params.safe_beyond_raw ? ", safe range beyond the raw one allowed" : "",
                noise.c_str(), params.zones.StoppingDistanceM(), s > 0 ? n / s : 0.0, out.c_str());
  } catch (const std::exception& e) {
    return Error(e.what());
  }
  return blind > 0 ? apps::kExitRowsFailed : apps::kExitOk;
}
