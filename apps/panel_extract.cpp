// panel_extract: finds the panel in RealSense recordings and writes one row of panel metrics per
// recording (DESIGN.md's CSV), and optionally panels.json with what each detection found.
#include <unistd.h>

#include <atomic>
#include <iostream>
#include <memory>
#include <mutex>
#include <thread>

#include "args.h"
#include "camera/presets.h"
#include "io/atomic_file.h"
#include "io/bag.h"
#include "io/bag_list.h"
#include "io/config_file.h"
#include "io/manifest.h"
#include "io/metrics_csv.h"
#include "io/temp_files.h"
#include "panel/extract.h"
#include "panel/prefetch.h"

using namespace depthbias;

namespace {

// A mistake on the command line (as apps::Args reports them): the message points to --help.
using UsageError = std::invalid_argument;

const char* kUsage =
    "usage: panel_extract [options] BAG_OR_DIR...\n"
    "Finds the panel in each recording (folders searched for *.bag) and writes one row of\n"
    "panel metrics per recording. Options (default):\n"
    "  --manifest CSV       ground truth per bag: distance_m, angle_deg, light (none)\n"
    "  --config YAML        panel parameters overriding the defaults (none)\n"
    "  --out FILE           metrics CSV (metrics.csv)\n"
    "  --panels-out FILE    what each detection found, JSON (none)\n"
    "  --jobs N             recordings measured at once, 1 to 256 (1)\n"
    "  --region-mode MODE   auto|box (auto)\n"
    "  --boxes JSON         boxes of box mode {\"name.bag\": [u0, v0, u1, v1]} (none)\n"
    "  --quiet              no progress and no summary line (off)\n";

class BagSource : public panel::FrameSource {
 public:
  explicit BagSource(std::string path) : path_(std::move(path)) { Rewind(); }
  const io::BagInfo& info() const { return reader_->info(); }
  bool Next(records::DepthFrame* f) override { return reader_->Next(f); }
  bool Rewind() override {
    reader_ = std::make_unique<io::BagReader>(path_);
    return true;
  }

 private:
  std::string path_;
  std::unique_ptr<io::BagReader> reader_;
};

struct Options {
  std::string manifest, config, out = "metrics.csv", panels_out, boxes, mode = "auto";
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

void Run(Job* job, const Options& o, const panel::PanelParams& params,
         const io::Manifest* manifest, const std::map<std::string, std::array<double, 4>>& boxes) {
  records::PanelMetrics& m = job->row;
  const std::string name = io::BaseName(job->path);
  m.bag = name;
  panel::ExtractResult r;
  camera::Intrinsics in;
  try {
    if (!job->problem.empty()) throw std::runtime_error(job->problem);
    const io::ManifestRow* truth = manifest ? manifest->Find(job->path) : nullptr;
    if (manifest && !truth) throw std::runtime_error("not listed in " + manifest->file());
    if (truth) {
      m.distance_m = truth->distance_m;
      m.angle_deg = truth->angle_deg;
      m.light = truth->light;
    }
    std::optional<panel::PixelBox> box;
    if (o.mode == "box") {
      const auto b = boxes.find(name);
      if (b == boxes.end()) throw std::runtime_error("no box for it in " + o.boxes);
      box = panel::PixelBox{b->second[0], b->second[1], b->second[2], b->second[3]};
    }
    BagSource source(job->path);
    const io::BagInfo& info = source.info();
    if (!info.has_depth_intrinsics) throw std::runtime_error("no depth intrinsics recorded");
    in = info.depth_intrinsics;
    panel::SearchWindow window;
    if (truth) window = {truth->distance_m, truth->angle_deg};
    const auto preset = info.options.find("Visual_Preset");
    const auto emitter = info.options.find("Emitter_Enabled");
    if (preset != info.options.end()) m.preset = camera::PresetName(preset->second);
    if (emitter != info.options.end()) m.emitter = emitter->second != 0 ? "on" : "off";
    panel::PrefetchSource ahead(&source, 8);  // read on one core, measure on the other
    r = panel::ExtractPanel(ahead, in, params, window, box);
    if (truth && truth->preset) m.preset = *truth->preset;
    if (truth && truth->emitter) m.emitter = *truth->emitter;
    const records::PanelMetrics known = m;  // what the manifest and the bag say
    m = r.metrics;
    m.bag = known.bag;
    m.light = known.light;
    m.preset = known.preset;
    m.emitter = known.emitter;
    m.distance_m = known.distance_m;
    m.angle_deg = known.angle_deg;
  } catch (const std::exception& e) {
    const std::string what =
        dynamic_cast<const std::bad_alloc*>(&e) ? "out of memory while reading it" : e.what();
    m.status = "error";
    m.message = what.rfind(job->path, 0) == 0 ? what : job->path + ": " + what;
  }
  r.metrics = m;
  job->json = panel::DetectionJson(r, in, "\"bag\": \"" + name + "\"");
}

}  // namespace

int main(int argc, char** argv) {
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
      else if (a == "--quiet") o.quiet = true;
      else if (args.IsHelp()) return std::cout << kUsage << apps::kExitHelp, apps::kExitOk;
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
  std::atomic<std::size_t> next{0}, done{0};
  std::mutex print;
  auto worker = [&] {
    for (std::size_t k; (k = next++) < jobs.size();) {
      Run(&jobs[k], o, params, manifest.get(), boxes);
      std::lock_guard<std::mutex> lock(print);
      ++done;
      if (!jobs[k].row.ok())
        std::cerr << (progress ? "\r\033[K" : "") << jobs[k].row.bag << ": "
                  << jobs[k].row.status << ": " << jobs[k].row.message << "\n";
      if (progress)
        std::cerr << "\r\033[K[" << done << "/" << jobs.size() << "] " << jobs[k].row.bag
                  << std::flush;
    }
  };
  std::vector<std::thread> threads;
  for (int t = 0; t < std::min<int>(o.jobs, static_cast<int>(jobs.size())); ++t)
    threads.emplace_back(worker);
  for (std::thread& t : threads) t.join();
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
