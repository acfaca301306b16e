#pragma once
// The weights YAML of DESIGN.md ("File formats"): the record a fit writes and a machine loads.
//
//   schema: depthbias.weights/2
//   model: disp_knots          target: median_m - distance_m      lambda: 0.001
//   loss: huber                loss_scale_m: 1      focal_px: 640  baseline_m: 0.095
//   group_by: [light, preset]
//   near_guard: {near_m: 5, full_m: 7}        noise_pooled: true
//   groups:
//     - {light, preset, [emitter], n, weights: {name: value, ...}, [knots_deg: [...]],
//        rmse_m, mae_m, residual_std_m,
//        [margin: {placement_m, noise_per_m, weighted, [errors: held_out|in_sample]}],
//        [disparity_noise: {sigma_px, recordings}],
//        cv: {scheme: point|distance|angle|none, rmse_m, mae_m}, [cv_more: [...]],
//        covariance: [[...], ...]}
//   provenance: {input_file, input_sha256, tool, tool_version}
//
// Schema depthbias.weights/1 (before margins: no near_guard, noise_pooled, margin) is still
// read; its groups have margin.known = false and their predictive σ is the constant residual std
// of that time. Files are always written as /2. `disparity_noise` (the unit's σ_d in the group's
// scenario: the median of its recordings' sigma_d_px and how many) is optional: files written
// before it, or from tables that did not measure it, read with disparity_noise.known = false.

#include <string>

#include "records/bias_weights.h"
#include "io/io_error.h"

namespace depthbias::io {

std::string FormatWeightsYaml(const records::BiasWeights& weights);
void WriteWeightsYaml(const std::string& path, const records::BiasWeights& weights);

// Throws IoError naming the file and the key for a YAML of another schema, a missing key, a
// value of the wrong type, or one without physical meaning (ranges.h: a knot at 80° or beyond,
// a σ term whose square overflows).
records::BiasWeights ParseWeightsYaml(const std::string& text, const std::string& file);
records::BiasWeights ReadWeightsYaml(const std::string& path);

}  // namespace depthbias::io
