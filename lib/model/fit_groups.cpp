#include "model/fit_groups.h"

#include <chrono>

namespace depthbias::model {

bool FitGroupsParams::IsValid(std::string* why) const {
  if (!fit.IsValid(why)) return false;
  for (const auto& k : group_by) {
    if (k != "light" && k != "preset" && k != "emitter") {
      if (why) *why = "unknown grouping key '" + k + "' (known: light, preset, emitter)";
      return false;
    }
  }
  return true;
}

FitReport FitGroups(const std::vector<camera::PanelMetrics>& rows,
                    const FitGroupsParams& params) {
  FitReport report;
  const auto start = std::chrono::steady_clock::now();
  std::string why;
  if (!params.IsValid(&why)) {
    report.message = why;
    return report;
  }
  for (const auto& r : rows) (r.ok() ? report.rows_used : report.rows_skipped)++;
  if (report.rows_used == 0) {
    report.message = "no row with status ok to fit";
    return report;
  }
  for (const auto& g : GroupRows(rows, params.group_by)) {
    GroupReport gr;
    gr.group = g;
    const auto samples = MakeSamples(rows, g.rows, params.fit.weight_by_valid_pixels);
    gr.fit = Fit(samples, params.fit);
    if (!gr.fit.success) {
      report.message = "group " + g.Label() + ": " + gr.fit.message;
      return report;
    }
    for (CvScheme s : params.cv) {
      if (s == CvScheme::kNone) continue;
      gr.cv.push_back(CrossValidate(samples, params.fit, s));
      if (!gr.cv.back().success) {
        report.message = "group " + g.Label() + ": " + CvSchemeName(s) +
                         " cross-validation: " + gr.cv.back().message;
        return report;
      }
    }
    report.groups.push_back(std::move(gr));
  }
  report.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report.success = true;
  return report;
}

camera::BiasWeights ToWeights(const FitReport& report, const FitGroupsParams& params) {
  camera::BiasWeights w;
  w.model = params.fit.model;
  w.lambda = params.fit.lambda;
  w.loss = LossName(ResolveLoss(params.fit.loss, params.fit.model));
  w.loss_scale_m = params.fit.loss_scale_m;
  w.focal_px = params.fit.focal_px;
  w.baseline_m = params.fit.baseline_m;
  w.group_by = params.group_by;
  for (const auto& gr : report.groups) {
    camera::BiasWeightsGroup g;
    g.light = gr.group.light;
    g.preset = gr.group.preset;
    g.emitter = gr.group.emitter;
    g.n = gr.fit.n;
    g.names = gr.fit.names;
    g.values = gr.fit.values;
    g.knots_deg = gr.fit.constants.knots_deg;
    g.rmse_m = gr.fit.rmse_m;
    g.mae_m = gr.fit.mae_m;
    g.residual_std_m = gr.fit.residual_std_m;
    for (const auto& cv : gr.cv) g.cv.push_back({CvSchemeName(cv.scheme), cv.rmse_m, cv.mae_m});
    if (gr.fit.covariance_ok) {
      const auto& c = gr.fit.covariance;
      for (Eigen::Index i = 0; i < c.rows(); ++i) {
        std::vector<double> row;
        for (Eigen::Index j = 0; j < c.cols(); ++j) row.push_back(c(i, j));
        g.covariance.push_back(row);
      }
    }
    w.groups.push_back(std::move(g));
  }
  return w;
}

}  // namespace depthbias::model
