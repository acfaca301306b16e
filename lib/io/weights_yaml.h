#pragma once
// The weights YAML of DESIGN.md ("File formats"): the record a fit writes and a machine loads.
//
//   schema: depthbias.weights/1
//   model: disp_knots          target: median_m - distance_m      lambda: 0.001
//   loss: huber                loss_scale_m: 1      focal_px: 640  baseline_m: 0.095
//   group_by: [light, preset]
//   groups:
//     - {light, preset, [emitter], n, weights: {name: value, ...}, [knots_deg: [...]],
//        rmse_m, mae_m, residual_std_m, cv: {scheme, rmse_m, mae_m}, [cv_more: [...]],
//        covariance: [[...], ...]}
//   provenance: {input_file, input_sha256, tool, tool_version}

#include <string>

#include "records/bias_weights.h"
#include "io/io_error.h"

namespace depthbias::io {

std::string FormatWeightsYaml(const records::BiasWeights& weights);
void WriteWeightsYaml(const std::string& path, const records::BiasWeights& weights);

// Throws IoError naming the file and the key for a YAML of another schema, a missing key or a
// value of the wrong type.
records::BiasWeights ParseWeightsYaml(const std::string& text, const std::string& file);
records::BiasWeights ReadWeightsYaml(const std::string& path);

}  // namespace depthbias::io
