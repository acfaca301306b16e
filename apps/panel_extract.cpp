// panel_extract: finds the panel in RealSense recordings and writes one row of panel metrics per
// recording (DESIGN.md's CSV), and optionally panels.json with what each detection found.
#include <unistd.h>

#include <iostream>
#include <memory>
#include <optional>
#include <mutex>

#include "args.h"
#include "memory.h"
#include "common/parallel.h"
#include "io/atomic_file.h"
#include "io/bag.h"
#include "io/bag_list.h"
#include "io/config_file.h"
#include "io/manifest.h"
#include "io/metrics_csv.h"
#include "io/temp_files.h"
#include "panel/params.h"
#include "pipeline/extract_recording.h"

using namespace depthbias;

namespace {

// A mistake on the command line (as apps::Args reports them): the message points to --help.
using UsageError = std::invalid_argument;

const char* kUsage =
    "usage: panel_extract [options] RECORDING_OR_DIR...\n"
    "Finds the panel in each recording (ROS 1 .bag; rosbag2 folder, .mcap or .db3; folders\n"
    "searched for them) and writes one row of panel metrics per recording. Options (default):\n"
    "  --manifest CSV       ground truth per bag: distance_m, angle_deg, light (none)\n"
    "  --config YAML        panel parameters overriding the defaults (none)\n"
    "  --out FILE           metrics CSV (metrics.csv)\n"
    "  --panels-out FILE    what each detection found, JSON (none)\n"
    "  --jobs N             recordings measured at once, 1 to 256 (1)\n"
    "  --region-mode MODE   auto|box (auto)\n"
    "  --boxes JSON         boxes of box mode {\"name.bag\": [u0, v0, u1, v1]} (none)\n"
    "  --topic T            depth topic of ROS 2 recordings (found by type and name)\n"
    "  --quiet              no progress and no summary line (off)\n";

struct Options {
  std::string manifest, config, out = "metrics.csv", panels_out, boxes, mode = "auto", topic;
  int jobs = 1;
  bool quiet = false;
  std::vector<std::string> inputs;
};

struct Job {
  std::string path;
  records::PanelMetrics row;
  std::string json;
  std::string problem;  // found by the folder search: an error row without reading
};

}  // namespace

int main(int argc, char** argv) {
  apps::KeepLargeBlocksForReuse();
  io::PrepareRosEnvironment();
  io::InstallSignalCleanup();
  Options o;
  panel::PanelParams params;
  std::unique_ptr<io::Manifest> manifest;
  std::map<std::string, std::array<double, 4>> boxes;
  std::vector<Job> jobs;
  try {
    for (apps::Args args(argc, argv); args.Next();) {
      const std::string& a = args.flag();
      auto value = [&] { return args.Value(); };
      if (a == "--manifest") o.manifest = value();
      else if (a == "--config") o.config = value();
      else if (a == "--out") o.out = value();
      else if (a == "--panels-out") o.panels_out = value();
      else if (a == "--boxes") o.boxes = value();
      else if (a == "--region-mode") o.mode = value();
      else if (a == "--jobs") o.jobs = static_cast<int>(args.Number(true, 1, 256));
      else if (a == "--topic") o.topic = value();
      else if (a == "--quiet") o.quiet = true;
      else if (args.IsHelp()) return apps::PrintHelp(kUsage);
      else if (a.rfind("--", 0) == 0) throw UsageError("unknown option " + a);
      else o.inputs.push_back(a);
    }
    if (o.inputs.empty()) throw UsageError("no recording given");
    if (o.mode != "auto" && o.mode != "box") throw UsageError("--region-mode auto|box");
    if (o.mode == "box" && o.boxes.empty()) throw UsageError("box mode needs --boxes");
    if (!o.config.empty()) {
      for (const io::ConfigEntry& e : io::ReadConfigScalars(o.config)) {
        std::string why;
        if (!params.Set(e.key, e.value, &why))
          throw std::runtime_error(o.config + ":" + std::to_string(e.line) + ": " + why);
      }
    }
    std::string why;
    if (!params.IsValid(&why)) throw std::runtime_error(o.config + ": " + why);
    if (!o.manifest.empty()) manifest = std::make_unique<io::Manifest>(io::ReadManifest(o.manifest));
    if (!o.boxes.empty()) boxes = io::ReadBoxes(o.boxes);
    std::vector<std::string> inputs = {o.manifest, o.config, o.boxes};
    for (const io::ListedBag& bag : io::ListBags(o.inputs)) {
      jobs.push_back({bag.path, {}, {}, bag.problem});
      inputs.push_back(bag.path);
    }
    io::CheckOutputs({o.out, o.panels_out}, inputs);
    io::CheckOutputFile(o.out);  // before the work, not after it
    if (!o.panels_out.empty()) io::CheckOutputFile(o.panels_out);
  } catch (const UsageError& e) {
    std::cerr << "panel_extract: " << e.what() << " (see panel_extract --help)\n";
    return apps::kExitError;
  } catch (const std::exception& e) {
    std::cerr << "panel_extract: " << e.what() << "\n";
    return apps::kExitError;
  }

  const bool progress = !o.quiet && isatty(STDERR_FILENO);
  std::size_t done = 0;
  std::mutex print;
  common::ForEachIndex(jobs.size(), o.jobs, [&](std::size_t k) {
    std::optional<panel::PixelBox> box;
    if (o.mode == "box") {
      const auto b = boxes.find(io::BaseName(jobs[k].path));
      if (b != boxes.end()) box = panel::PixelBox{b->second[0], b->second[1], b->second[2], b->second[3]};
    }
    pipeline::RecordingResult r;
    if (!jobs[k].problem.empty()) {  // found by the folder search: no need to read it
      r.row.bag = io::BaseName(jobs[k].path);
      r.row.status = "error";
      r.row.message = jobs[k].problem.rfind(jobs[k].path, 0) == 0
                          ? jobs[k].problem
                          : jobs[k].path + ": " + jobs[k].problem;
    } else if (o.mode == "box" && !box) {
      r.row.bag = io::BaseName(jobs[k].path);
      r.row.status = "error";
      r.row.message = jobs[k].path + ": no box for it in " + o.boxes;
    } else {
      r = pipeline::ExtractRecording(jobs[k].path, params, manifest.get(), box, {o.topic});
    }
    jobs[k].row = r.row;
    jobs[k].json = r.detection_json;
    std::lock_guard<std::mutex> lock(print);
    ++done;
    if (!jobs[k].row.ok())
      std::cerr << (progress ? "\r\033[K" : "") << jobs[k].row.bag << ": "
                << jobs[k].row.status << ": " << jobs[k].row.message << "\n";
    if (progress)
      std::cerr << "\r\033[K[" << done << "/" << jobs.size() << "] " << jobs[k].row.bag
                << std::flush;
  });
  if (progress) std::cerr << "\r\033[K";

  std::vector<records::PanelMetrics> rows;
  std::string json = "[\n";
  bool all_ok = true;
  std::map<std::string, std::size_t> by_status;
  for (const Job& j : jobs) {
    rows.push_back(j.row);
    json += (rows.size() > 1 ? ",\n" : "") + j.json;
    all_ok = all_ok && j.row.ok();
    ++by_status[j.row.status];
  }
  try {
    std::vector<std::pair<std::string, std::string>> files = {{o.out, io::FormatMetricsCsv(rows)}};
    if (!o.panels_out.empty()) files.push_back({o.panels_out, json + "\n]\n"});
    io::WriteFilesAtomic(files);  // both or neither
  } catch (const std::exception& e) {
    std::cerr << "panel_extract: " << e.what() << "\n";
    return apps::kExitError;
  }
  if (!o.quiet)
    std::cerr << "panel_extract: " << apps::Summary(rows.size(), "recording", by_status, o.out)
              << "\n";
  return all_ok ? apps::kExitOk : apps::kExitRowsFailed;
}
