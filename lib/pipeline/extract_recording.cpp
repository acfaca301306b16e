#include "pipeline/extract_recording.h"

#include <cmath>
#include <new>
#include <stdexcept>

#include "camera/presets.h"
#include "io/atomic_file.h"
#include "io/recording.h"
#include "panel/prefetch.h"

namespace depthbias::pipeline {

RecordingResult ExtractRecording(const std::string& path, const panel::PanelParams& params,
                                 const io::Manifest* manifest,
                                 const std::optional<panel::PixelBox>& box,
                                 const io::RecordingOptions& recording) {
  RecordingResult out;
  records::PanelMetrics& m = out.row;
  const std::string name = io::BaseName(path);
  m.bag = name;
  panel::ExtractResult r;
  camera::Intrinsics in;
  std::string disagree;  // where the manifest and the recording differ
  std::string settings;  // where preset and emitter came from
  std::string damage_note;  // the recording was cut short
  try {
    const io::ManifestRow* truth = manifest ? manifest->Find(path) : nullptr;
    if (manifest && !truth) throw std::runtime_error("not listed in " + manifest->file());
    if (truth) {
      m.distance_m = truth->distance_m;
      m.angle_deg = truth->angle_deg;
      m.light = truth->light;
    }
    const std::unique_ptr<io::RecordingSource> source = io::OpenRecording(path, recording);
    const io::BagInfo& info = source->info();
    if (!info.has_depth_intrinsics) throw std::runtime_error("no depth intrinsics recorded");
    in = info.depth_intrinsics;
    panel::SearchWindow window;
    if (truth) window = {truth->distance_m, truth->angle_deg};
    const auto preset = info.options.find("Visual_Preset");
    const auto emitter = info.options.find("Emitter_Enabled");
    if (preset != info.options.end()) m.preset = camera::PresetName(preset->second);
    if (emitter != info.options.end()) m.emitter = emitter->second != 0 ? "on" : "off";
    settings = source->settings_source();
    if (truth && (truth->preset || truth->emitter)) settings = "manifest";
    // The manifest's word wins (it is the user's), but never silently: a disagreement with what
    // the recording says is written in the row's message.
    auto compare = [&](const std::optional<std::string>& listed, bool recorded,
                       const std::string& bag_value, const char* what, const char* option) {
      if (!listed || !recorded || *listed == bag_value) return;
      disagree += std::string(disagree.empty() ? "" : "; ") + "the manifest's " + what + " '" +
                  *listed + "' differs from the recording's " + option + " '" + bag_value +
                  "' (the manifest's is used)";
    };
    if (truth) {
      compare(truth->preset, preset != info.options.end(), m.preset, "preset", "Visual_Preset");
      compare(truth->emitter, emitter != info.options.end(), m.emitter, "emitter",
              "Emitter_Enabled");
      if (truth->preset) m.preset = *truth->preset;
      if (truth->emitter) m.emitter = *truth->emitter;
    }
    // B of the metrics in disparity units (subpixel_rms_px, sigma_d_px): the recording's own
    // Stereo_Baseline [mm] when it holds one, else the configured one.
    panel::PanelParams used = params;
    const auto baseline = info.options.find("Stereo_Baseline");
    if (baseline != info.options.end() && baseline->second > 0 &&
        std::isfinite(baseline->second))
      used.baseline_m = baseline->second / 1000.0;
    panel::PrefetchSource ahead(source.get(), 8);  // read on one core, measure on the other
    r = panel::ExtractPanel(ahead, in, used, window, box);
    // A recording cut short (a bare MCAP file whose writer stopped, a ROS 1 bag read with
    // allow_partial) gives its frames up to the damage; its row says so.
    if (!source->damage().empty())
      damage_note = path + ": read up to where it stops being readable (" +
                        source->damage() + ")";
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
    m.message = what.rfind(path, 0) == 0 ? what : path + ": " + what;
  }
  if (!disagree.empty()) {
    const std::string note = manifest->file() + ": " + disagree;
    m.message = m.message.empty() ? note : m.message + "; " + note;
  }
  if (!damage_note.empty())
    m.message = m.message.empty() ? damage_note : m.message + "; " + damage_note;
  r.metrics = m;
  out.detection_json = panel::DetectionJson(
      r, in, "\"bag\": \"" + name + "\", \"settings_from\": \"" +
                 (settings.empty() ? "none" : settings) + "\"");
  return out;
}

}  // namespace depthbias::pipeline
