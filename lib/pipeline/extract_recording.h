#pragma once
// One recording's extraction as panel_extract runs it: the recording (ROS 1 bag or rosbag2, see
// io/recording.h) read through io, the ground truth
// the bag cannot know merged from its manifest row (distance, angle, light, and preset and
// emitter when the manifest gives them, otherwise the bag's recorded Visual_Preset and
// Emitter_Enabled options), the panel found and measured, and every failure turned into a row
// with status "error" or "no_panel" and a message naming the file, so a batch goes on.

#include <optional>
#include <string>

#include "io/manifest.h"
#include "io/recording.h"
#include "panel/extract.h"
#include "panel/params.h"
#include "records/panel_metrics.h"

namespace depthbias::pipeline {

struct RecordingResult {
  records::PanelMetrics row;   // one row of the metrics CSV
  std::string detection_json;  // its panels.json entry
};

// manifest: nullptr when none was given; a manifest without a row for the recording (matched by
// path, io::Manifest::Find) makes an error row. Where the manifest's preset or emitter differs
// from the one the recording holds, the manifest's is used and the row's message says so.
// box: the article's manual method instead of the automatic detection. The detection's JSON says
// where preset and emitter came from ("settings_from": manifest, recorded options, parameter
// messages or none).
RecordingResult ExtractRecording(const std::string& path, const panel::PanelParams& params,
                                 const io::Manifest* manifest,
                                 const std::optional<panel::PixelBox>& box = std::nullopt,
                                 const io::RecordingOptions& recording = {});

}  // namespace depthbias::pipeline
