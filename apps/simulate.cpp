// simulate: the simulated D455 on a protocol (lib/sim): bags and their manifest, the metrics-only
// table, or the base sensor calibrated to a real table (see kUsage). --threads N: recordings
// simulated in parallel (default: all cores; results do not depend on it).
#include <glog/logging.h>

#include <cstdio>
#include <filesystem>
#include <functional>
#include <mutex>
#include <iostream>
#include <memory>
#include <string>
#include <thread>

#include "args.h"
#include "camera/presets.h"
#include "gap/calibrate.h"
#include "io/atomic_file.h"
#include "io/bag.h"
#include "io/csv.h"
#include "io/manifest.h"
#include "io/mcap_writer.h"
#include "io/metrics_csv.h"
#include "io/recording.h"
#include "io/temp_files.h"
#include "io/yaml_limits.h"
#include "sim/config_yaml.h"
#include "sim/render_protocol.h"

namespace {

using namespace depthbias;
namespace fs = std::filesystem;

constexpr char kUsage[] =
    "usage: simulate --protocol P.yaml --out-dir DIR            bags + DIR/manifest.csv\n"
    "       simulate --protocol P.yaml --metrics-only --out metrics.csv\n"
    "       simulate --protocol P.yaml --calibrate-to real.csv --out sensor.yaml\n"
    "Simulates the D455 on a protocol: RealSense bags with their ground truth, the panel\n"
    "metrics directly (fast path), or the base sensor calibrated to a real metrics table.\n"
    "A run's bags and manifest are written all or none. Options (default):\n"
    "  --protocol FILE      protocol YAML (required)\n"
    "  --out-dir DIR        write bags and DIR/manifest.csv (one of these three modes)\n"
    "  --metrics-only       write the metrics table to --out\n"
    "  --calibrate-to CSV   fit the base sensor to a real table, write it to --out\n"
    "  --out FILE           output of --metrics-only and --calibrate-to\n"
    "  --format F           recordings of --out-dir: bag (RealSense ROS 1) or rosbag2 (MCAP,\n"
    "                       zstd chunks, the ROS 2 wrapper's topics) (bag)\n"
    "  --frames N           frames per recording, 1 to 100000 (the protocol's)\n"
    "  --seed S             seed of every random draw (0)\n"
    "  --effects FILE       effects YAML added to the base sensor (none)\n"
    "  --sensor FILE        sensor YAML, or builtin (the protocol's sensor file)\n"
    "  --sensor-from BAG    take the depth intrinsics, units and Stereo_Baseline of a\n"
    "                       recording (none)\n"
    "  --margin-px M        region margin of the metrics [px], >= 0 (the metrics default)\n"
    "  --threads N          recordings simulated in parallel, 1 to 256 (all cores)\n";
constexpr int kMaxFrames = 100000;  // about 55 min at 30 fps per recording

struct Fail : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string Fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

// ext: ".bag" (RealSense ROS 1) or ".mcap" (rosbag2), as --format says.
std::string BagPath(const std::string& dir, const sim::Cell& cell, const std::string& ext) {
  return (fs::path(dir) / (cell.name + ext)).string();
}

// Before any work: the bags (and their .part) and the manifest of --out-dir are new outputs
// (none an input, no two alike: duplicate distances in a protocol name two recordings alike),
// the folder is writable and has room for them.
void CheckRecordings(const sim::SimParams& params, const std::string& dir,
                     const std::vector<std::string>& inputs, const std::string& ext) {
  std::vector<std::string> names = {"manifest.csv"};
  const std::vector<sim::Cell> cells = sim::MakeCells(params.protocol);
  for (const sim::Cell& cell : cells) {
    names.push_back(cell.name + ext);
    names.push_back(cell.name + ext + ".part");
  }
  const auto& in = params.sensor.intrinsics;
  const double frame_bytes = 2.0 * in.width * in.height + 2048.0;  // pixels and message
  io::CheckOutputSet(dir, names, inputs,
                     static_cast<double>(cells.size()) *
                         (params.protocol.frames * frame_bytes + 65536.0));
}

// A recording's output through a BagWriter or an McapWriter (the same Finish / Commit contract).
template <typename Writer>
sim::RecordingOutput Output(std::shared_ptr<Writer> writer, const sim::Cell& cell,
                            apps::Progress* progress, std::mutex* mutex,
                            std::vector<std::function<void()>>* commits) {
  {
    std::lock_guard<std::mutex> lock(*mutex);
    commits->push_back([writer] { writer->Commit(); });
  }
  return sim::RecordingOutput{[writer](const records::DepthFrame& f) { writer->Write(f); },
                              [writer, progress, name = cell.name] {
                                writer->Finish();
                                progress->Step(name);
                              }};
}

// Every recording of the protocol as a bag in dir, then DIR/manifest.csv with each recording's
// truth. Bags stay DIR/NAME.bag.part until every recording is finished, then all are renamed
// into place and the manifest written; the first error (or a signal) removes them all.
void WriteRecordings(const sim::SimParams& params, const sim::MetricsParams& metrics,
                     const std::string& dir, const std::string& ext) {
  fs::create_directories(dir);
  std::mutex mutex;
  std::vector<std::function<void()>> commits;
  apps::Progress progress(sim::MakeCells(params.protocol).size());
  auto open = [&](const sim::Cell& cell) {
    io::BagWriterConfig config;
    config.intrinsics = params.sensor.intrinsics;
    config.depth_units_m = params.sensor.depth_units_m;
    config.fps = params.protocol.fps;
    camera::PresetOptionValue(cell.preset, &config.options["Visual_Preset"]);
    config.options["Emitter_Enabled"] = cell.emitter_on ? 1 : 0;
    config.options["Stereo_Baseline"] = params.sensor.baseline_m * 1000.0;  // [mm]
    config.device = {{"Name", "Intel RealSense D455"}, {"Serial Number", "depthbias-sim"}};
    const std::string path = BagPath(dir, cell, ext);
    if (ext == ".mcap")
      return Output(std::make_shared<io::McapWriter>(path, io::McapWriterConfig{config}), cell,
                    &progress, &mutex, &commits);
    return Output(std::make_shared<io::BagWriter>(path, config), cell, &progress, &mutex,
                  &commits);
  };
  std::vector<io::ManifestRow> rows;
  for (const sim::RenderedRecording& r :
       sim::RenderProtocol(params, metrics, metrics.threads, open)) {
    io::ManifestRow row;
    row.bag = r.cell.name + ext;
    row.distance_m = r.cell.distance_m;
    row.angle_deg = r.cell.angle_deg;
    row.light = r.cell.light;
    row.preset = r.cell.preset;
    row.emitter = r.cell.emitter_on ? "on" : "off";
    const sim::CellTruth& truth = r.truth.truth;
    row.extras = {{"true_depth_m", Fixed(truth.panel_depth_m, 6)},
                  {"true_range_m", Fixed(truth.panel_range_m, 6)},
                  {"true_angle_deg", Fixed(truth.panel_angle_deg, 4)},
                  {"true_hole_rate_pct", Fixed(r.truth.metrics.hole_rate_pct, 3)}};
    rows.push_back(row);
  }
  // Obstacle scenes: where each obstacle's face towards the camera is (the same in every
  // recording of the protocol).
  std::vector<std::vector<std::string>> obstacles;
  for (const sim::ObstaclePose& o : sim::PlaceObstacles(params.protocol.scene))
    obstacles.push_back({o.obstacle.kind, Fixed(o.face_range_m, 6), Fixed(o.face_azimuth_deg, 4),
                         Fixed(o.face_center_m.x(), 6), Fixed(o.face_center_m.y(), 6),
                         Fixed(o.face_center_m.z(), 6)});
  progress.Clear();
  {
    const io::CommitScope all_or_none;  // a signal now waits for the last rename
    for (const auto& commit : commits) commit();
    io::WriteManifest((fs::path(dir) / "manifest.csv").string(), rows,
                      {"true_depth_m", "true_range_m", "true_angle_deg", "true_hole_rate_pct"});
    if (!obstacles.empty())
      io::WriteCsv((fs::path(dir) / "obstacles.csv").string(),
                   {"kind", "range_m", "azimuth_deg", "x_m", "y_m", "z_m"}, obstacles);
  }
  std::printf("simulate: %zu recordings of %d frames in %s\n", rows.size(),
              params.protocol.frames, dir.c_str());
}

void Calibrate(const sim::SimParams& params, const std::string& real_csv,
               const std::string& out, const sim::MetricsParams& metrics) {
  gap::CalibrateParams cp;
  cp.metrics = metrics;
  const gap::CalibrationResult r =
      gap::CalibrateSensor(params, io::ReadMetricsCsv(real_csv), cp);
  if (!r.success) throw Fail(real_csv + ": calibration failed: " + r.message);
  std::fputs(gap::FormatCalibration(r).c_str(), stdout);
  io::WriteFileAtomic(
      out, sim::FormatSensorYaml(
               r.sensor,
               {"D455 base sensor calibrated by simulate --calibrate-to " +
                    io::BaseName(real_csv) + " (per scenario: sigma_d_px, invalid_prob)",
                "fitted to plane_std_m (relative) and valid_pct over every recording"},
               gap::CalibrationYaml(r, io::BaseName(real_csv))));
}

// The camera of a real recording: its depth intrinsics (rectified: distortion is dropped, with a
// warning if the recording has any), depth units and Stereo_Baseline.
void SensorFromRecording(const std::string& bag, sim::SensorParams* sensor) {
  const std::unique_ptr<io::RecordingSource> reader = io::OpenRecording(bag);
  const io::BagInfo& info = reader->info();
  if (!info.has_depth_intrinsics) throw Fail(bag + ": no camera_info for the depth stream");
  for (double c : info.depth_intrinsics.coeffs)
    if (c != 0) {
      std::cerr << "simulate: " << bag
                << ": distortion coefficients ignored (the simulated stream is rectified)\n";
      break;
    }
  sim::ApplyRecording(info.depth_intrinsics, info.depth_units_m, info.options, sensor);
}

}  // namespace

int main(int argc, char** argv) {
  FLAGS_minloglevel = google::GLOG_FATAL;  // Ceres (--calibrate-to) logs through glog
  FLAGS_logtostderr = true;
  google::InitGoogleLogging(argv[0]);
  io::PrepareRosEnvironment();
  io::InstallSignalCleanup();
  std::string protocol_file, sensor_file, sensor_bag, effects_file, out_dir, out, calibrate_to;
  bool metrics_only = false;
  std::string format = "bag";
  int frames = 0;
  sim::MetricsParams mp;
  mp.threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  sim::SimParams params;
  try {
    for (apps::Args args(argc, argv); args.Next();) {
      const std::string& a = args.flag();
      if (args.IsHelp()) return apps::PrintHelp(kUsage);
      auto value = [&] { return args.Value(); };
      if (a == "--protocol") protocol_file = value();
      else if (a == "--sensor") sensor_file = value();
      else if (a == "--sensor-from") sensor_bag = value();
      else if (a == "--effects") effects_file = value();
      else if (a == "--out-dir") out_dir = value();
      else if (a == "--out") out = value();
      else if (a == "--calibrate-to") calibrate_to = value();
      else if (a == "--format") format = value();
      else if (a == "--metrics-only") metrics_only = true;
      else if (a == "--frames") frames = static_cast<int>(args.Number(true, 1, kMaxFrames));
      else if (a == "--seed") params.seed = static_cast<std::uint64_t>(args.Number(true, 0, 9007199254740992.0));
      else if (a == "--margin-px") mp.region_margin_px = args.Number(false, 0);
      else if (a == "--threads") mp.threads = static_cast<int>(args.Number(true, 1, 256));
      else throw std::invalid_argument("unknown argument '" + a + "' (see simulate --help)");
    }
    if (protocol_file.empty()) throw Fail("--protocol FILE is required");
    if (format != "bag" && format != "rosbag2")
      throw std::invalid_argument("--format bag|rosbag2 (see simulate --help)");
    const std::string ext = format == "rosbag2" ? ".mcap" : ".bag";
    if ((out_dir.empty() ? 0 : 1) + metrics_only + !calibrate_to.empty() != 1)
      throw Fail("choose one of --out-dir DIR, --metrics-only, --calibrate-to real.csv");
    if ((metrics_only || !calibrate_to.empty()) && out.empty()) throw Fail("--out is required");
    std::string why, named_sensor;
    if (!sim::ParseProtocolYaml(io::ReadYamlFile(protocol_file), &params.protocol, &named_sensor,
                                &why))
      throw Fail(protocol_file + ": " + why);
    if (sensor_file.empty() && !named_sensor.empty())
      sensor_file = (fs::path(protocol_file).parent_path() / named_sensor).string();
    if (!sensor_file.empty() && sensor_file != "builtin" &&
        !sim::ParseSensorYaml(io::ReadYamlFile(sensor_file), &params.sensor, &why))
      throw Fail(sensor_file + ": " + why);
    if (!sensor_bag.empty()) SensorFromRecording(sensor_bag, &params.sensor);
    if (!effects_file.empty()) {
      std::vector<sim::EffectSpec> effects;
      if (!sim::ParseEffectsYaml(io::ReadYamlFile(effects_file), &effects, &why) ||
          !sim::BuildDepartures(effects, &params.departures, &why))
        throw Fail(effects_file + ": " + why);
    }
    const std::vector<std::string> inputs = {protocol_file, sensor_file, effects_file,
                                             calibrate_to, sensor_bag};
    if (frames != 0) params.protocol.frames = frames;
    if (!params.IsValid(&why) || !mp.IsValid(&why)) {
      std::string from = protocol_file;
      for (const std::string& f : {sensor_file, sensor_bag, effects_file})
        if (!f.empty() && f != "builtin") from += ", " + f;
      throw Fail(from + ": " + why);
    }
    if (params.protocol.frames > kMaxFrames)
      throw Fail(protocol_file + ": " + std::to_string(params.protocol.frames) +
                 " frames per recording, more than " + std::to_string(kMaxFrames));
    io::CheckOutputs({out}, inputs);
    if (!out.empty()) io::CheckOutputFile(out);  // before the work, not after it
    if (!out_dir.empty()) CheckRecordings(params, out_dir, inputs, ext);

    if (!out_dir.empty()) {
      WriteRecordings(params, mp, out_dir, ext);
    } else if (metrics_only) {
      std::vector<records::PanelMetrics> rows;
      for (const auto& r : sim::SimulateProtocolMetrics(params, mp)) rows.push_back(r.metrics);
      io::WriteMetricsCsv(out, rows);
    } else {
      Calibrate(params, calibrate_to, out, mp);
    }
  } catch (const std::bad_alloc&) {
    std::cerr << "simulate: " << protocol_file << ": out of memory while simulating it\n";
    return apps::kExitError;
  } catch (const std::exception& e) {
    std::cerr << "simulate: " << e.what() << "\n";
    return apps::kExitError;
  }
  return apps::kExitOk;
}
