#include "model/fit_groups.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>

#include "model/domain.h"
#include "model/margin_fit.h"
#include "model/select.h"

namespace depthbias::model {

bool FitGroupsParams::IsValid(std::string* why) const {
  if (!fit.IsValid(why)) return false;
  for (const auto& c : select)
    if (!c.IsValid(why)) return false;
  for (const auto& k : group_by) {
    if (k != "light" && k != "preset" && k != "emitter") {
      if (why) *why = "unknown grouping key '" + k + "' (known: light, preset, emitter)";
      return false;
    }
  }
  return true;
}

FitReport FitGroups(const std::vector<records::PanelMetrics>& rows,
                    const FitGroupsParams& params) {
  FitReport report;
  const auto start = std::chrono::steady_clock::now();
  std::string why;
  if (!params.IsValid(&why)) {
    report.message = why;
    return report;
  }
  for (const auto& r : rows) {
    if (r.ok() && !UsableForFit(r)) {
      report.message = "bag '" + r.bag + "' has no ground truth (distance_m or angle_deg " +
                       "empty): measure it with a manifest";
      return report;
    }
    if (UsableForFit(r)) {
      // A reading without physical meaning is refused, never fitted (domain.h).
      const std::string outside = OutsideDomain(r.median_m, r.angle_deg);
      if (!outside.empty()) {
        report.message = "bag '" + r.bag + "': " + outside;
        return report;
      }
    }
    (UsableForFit(r) ? report.rows_used : report.rows_skipped)++;
  }
  if (report.rows_used == 0) {
    report.message = "no row with status ok to fit";
    return report;
  }
  const auto groups = GroupRows(rows, params.group_by);
  std::vector<std::vector<Sample>> samples;
  for (const auto& g : groups) {
    samples.push_back(MakeSamples(rows, g.rows, params.fit.weight_by_valid_pixels));
  }
  // The point fit: given, or chosen by pooled held-out RMSE in metres (select.h).
  report.fitted = params.fit;
  std::unique_ptr<Selector> selector;
  if (!params.select.empty()) {
    selector = std::make_unique<Selector>(samples, params.select);
    const int c = selector->Choose(-1, nullptr, &why);
    if (c < 0) {
      report.message = why;
      return report;
    }
    report.chosen = c;
    report.fitted = params.select[static_cast<size_t>(c)];
    report.candidate_rmse_m = selector->PooledRmse();
    for (size_t i = 0; i < params.select.size(); ++i)
      report.candidate_labels.push_back(selector->Label(static_cast<int>(i)));
  }
  // Every scenario fitted with its margin, together (one camera: the noise term may be pooled).
  const JointFitResult joint = FitWithMargins(samples, report.fitted);
  if (!joint.success) {
    // Name the scenario that failed.
    for (size_t k = 0; k < groups.size(); ++k) {
      const FitResult f = Fit(samples[k], report.fitted);
      if (!f.success) {
        report.message = "group " + groups[k].Label() + ": " + f.message;
        return report;
      }
    }
    report.message = joint.message;
    return report;
  }
  // The scenarios' held-out errors under each candidate (for the pooled noise term of a fold
  // that chose it), computed once.
  std::map<int, std::vector<ResidualData>> errors_of;
  errors_of[report.chosen] = joint.errors;
  auto ErrorsOf = [&](int c) -> const std::vector<ResidualData>& {
    auto it = errors_of.find(c);
    if (it == errors_of.end()) {
      const JointFitResult j = FitWithMargins(samples, params.select[static_cast<size_t>(c)]);
      it = errors_of.emplace(c, j.success ? j.errors : std::vector<ResidualData>{}).first;
    }
    return it->second;
  };
  for (size_t k = 0; k < groups.size(); ++k) {
    if (joint.fits[k].margin_in_sample) {
      report.warnings.push_back("group " + groups[k].Label() + ": " + joint.fits[k].margin_note);
    }
  }
  for (size_t k = 0; k < groups.size(); ++k) {
    const Group& g = groups[k];
    GroupReport gr;
    gr.group = g;
    gr.samples = samples[k];
    gr.fit = joint.fits[k];
    gr.disparity_noise = GroupDisparityNoise(rows, g);
    // Cross-validation of the whole procedure; the other scenarios' errors stay as fitted.
    std::vector<ResidualData> others;
    for (size_t o = 0; o < joint.errors.size(); ++o)
      if (o != k) others.push_back(joint.errors[o]);
    for (CvScheme s : params.cv) {
      if (s == CvScheme::kNone) continue;
      if (selector) {
        // The choice is made again in every fold: the other scenarios' residual data as the
        // candidate chosen there gives them.
        auto fixed_for = [&](int c) {
          std::vector<ResidualData> out;
          const auto& errors = ErrorsOf(c);
          for (size_t o = 0; o < errors.size(); ++o)
            if (o != k) out.push_back(errors[o]);
          return out;
        };
        gr.cv.push_back(CrossValidateSelected(selector.get(), static_cast<int>(k), s, fixed_for));
      } else {
        gr.cv.push_back(params.fit.margins.enabled
                            ? CrossValidateWithMargins(samples[k], params.fit, s, others)
                            : CrossValidate(samples[k], params.fit, s));
      }
      if (!gr.cv.back().success) {
        gr.cv.back().rmse_m = gr.cv.back().mae_m = std::numeric_limits<double>::quiet_NaN();
        report.warnings.push_back("group " + g.Label() + ": no " + CvSchemeName(s) +
                                  " cross-validation: " + gr.cv.back().message);
      }
    }
    if (!params.nested_candidates.empty() && !params.cv.empty() &&
        params.cv.front() != CvScheme::kNone) {
      gr.nested = NestedCrossValidate(samples[k], params.nested_candidates, params.cv.front(),
                                      &gr.nested_chosen);
      if (!gr.nested.success) {
        gr.nested.rmse_m = std::numeric_limits<double>::quiet_NaN();
        report.warnings.push_back("group " + g.Label() + ": no nested cross-validation: " +
                                  gr.nested.message);
      }
    }
    report.groups.push_back(std::move(gr));
  }
  report.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report.success = true;
  return report;
}

records::BiasDisparityNoise GroupDisparityNoise(const std::vector<records::PanelMetrics>& rows,
                                               const Group& group) {
  records::BiasDisparityNoise out;
  if (group.preset == "*") return out;
  std::vector<double> v;
  for (size_t i : group.rows) {
    const double s = rows.at(i).sigma_d_px;
    if (std::isfinite(s) && s > 0) v.push_back(s);
  }
  if (v.empty()) return out;
  std::sort(v.begin(), v.end());
  const size_t mid = v.size() / 2;
  out.known = true;
  out.sigma_px = v.size() % 2 ? v[mid] : 0.5 * (v[mid - 1] + v[mid]);
  out.recordings = static_cast<int>(v.size());
  return out;
}

std::vector<FitParams> DefaultCandidates(const FitParams& base) {
  std::vector<FitParams> out;
  for (const auto& name : FormNames()) {
    for (Loss loss : {Loss::kNone, Loss::kHuber}) {
      FitParams p = base;
      p.model = name;
      p.loss = loss;
      p.priors.clear();
      out.push_back(p);
    }
  }
  return out;
}

std::string FormatFitTable(const FitReport& report, const FitGroupsParams& params) {
  std::string out;
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "model %s  loss %s (scale %g m)  lambda %g  rows %d used, %d skipped  %.3f s\n",
                report.fitted.model.c_str(),
                LossName(ResolveLoss(report.fitted.loss, report.fitted.model)).c_str(),
                report.fitted.loss_scale_m, report.fitted.lambda, report.rows_used,
                report.rows_skipped, report.seconds);
  out += buf;
  std::snprintf(buf, sizeof(buf), "%-20s %3s %8s %8s", "group", "n", "rmse_m", "mae_m");
  out += buf;
  for (CvScheme s : params.cv) {
    if (s == CvScheme::kNone) continue;
    const std::string n = CvSchemeName(s);
    std::snprintf(buf, sizeof(buf), " %14s %13s", (n + "_cv_rmse").c_str(),
                  (n + "_cv_mae").c_str());
    out += buf;
  }
  if (!params.nested_candidates.empty()) {
    std::snprintf(buf, sizeof(buf), " %12s", "nested_rmse");
    out += buf;
  }
  out += "  weights\n";
  for (const auto& g : report.groups) {
    std::snprintf(buf, sizeof(buf), "%-20s %3d %8.3f %8.3f", g.group.Label().c_str(), g.fit.n,
                  g.fit.rmse_m, g.fit.mae_m);
    out += buf;
    for (const auto& cv : g.cv) {
      std::snprintf(buf, sizeof(buf), " %14.3f %13.3f", cv.rmse_m, cv.mae_m);
      out += buf;
    }
    if (!params.nested_candidates.empty()) {
      std::snprintf(buf, sizeof(buf), " %12.3f", g.nested.rmse_m);
      out += buf;
    }
    out += " ";
    for (size_t j = 0; j < g.fit.names.size(); ++j) {
      std::snprintf(buf, sizeof(buf), " %s=%.3f", g.fit.names[j].c_str(), g.fit.values[j]);
      out += buf;
    }
    out += "\n";
  }
  if (report.chosen >= 0) {
    out += "point fit chosen by pooled held-out RMSE (leave a test point out):";
    for (size_t c = 0; c < report.candidate_labels.size(); ++c) {
      std::snprintf(buf, sizeof(buf), " %s%s %.3f", static_cast<int>(c) == report.chosen ? "*" : "",
                    report.candidate_labels[c].c_str(), report.candidate_rmse_m[c]);
      out += buf;
    }
    out += "\nchosen again in every fold (scheme: candidate: folds):\n";
    for (const auto& g : report.groups) {
      out += "  " + g.group.Label() + ":";
      for (const auto& cv : g.cv) {
        std::map<int, int> count;
        for (int c : cv.chosen) ++count[c];
        out += " " + CvSchemeName(cv.scheme) + "(";
        bool first = true;
        for (const auto& [c, k] : count) {
          out += (first ? "" : " ") + report.candidate_labels[static_cast<size_t>(c)] + ":" +
                 std::to_string(k);
          first = false;
        }
        out += ")";
      }
      out += "\n";
    }
  }
  if (!params.nested_candidates.empty()) {
    out += "nested choice (candidate: outer folds that chose it):\n";
    for (const auto& g : report.groups) {
      std::map<int, int> count;
      for (int c : g.nested_chosen) ++count[c];
      out += "  " + g.group.Label() + ":";
      for (const auto& [c, k] : count) {
        const auto& p = params.nested_candidates[static_cast<size_t>(c)];
        out += " " + p.model + "/" + LossName(ResolveLoss(p.loss, p.model)) + ":" +
               std::to_string(k);
      }
      out += "\n";
    }
  }
  std::string noise;
  for (const auto& g : report.groups) {
    if (!g.disparity_noise.known) continue;
    std::snprintf(buf, sizeof(buf), " %s %.4g px (%d)", g.group.Label().c_str(),
                  g.disparity_noise.sigma_px, g.disparity_noise.recordings);
    noise += buf;
  }
  if (!noise.empty())
    out += "disparity noise sigma_d (median of the recordings' sigma_d_px, recordings):" + noise +
           "\n";
  return out;
}

namespace {

// P(X ≥ m) for X ~ Binomial(n, p).
double BinomialUpperTail(int n, int m, double p) {
  if (m <= 0) return 1.0;
  if (p <= 0.0) return 0.0;
  double below = 0.0;  // P(X < m)
  for (int x = 0; x < m && x <= n; ++x) {
    const double log_term = std::lgamma(n + 1.0) - std::lgamma(x + 1.0) -
                            std::lgamma(n - x + 1.0) + x * std::log(p) +
                            (n - x) * std::log1p(-p);
    below += std::exp(log_term);
  }
  return std::clamp(1.0 - below, 0.0, 1.0);
}

}  // namespace

std::vector<CoverageRow> Coverage(const FitReport& report, double k, size_t scheme) {
  std::map<long long, CoverageRow> rows;
  const size_t groups = report.groups.size();
  for (size_t g = 0; g < groups; ++g) {
    const GroupReport& gr = report.groups[g];
    if (gr.cv.size() <= scheme || !gr.cv[scheme].success) continue;
    const CvResult& cv = gr.cv[scheme];
    const auto& samples = gr.samples;
    for (size_t i = 0; i < samples.size() && i < cv.errors_m.size(); ++i) {
      CoverageRow& row = rows[std::llround(samples[i].distance_m * 1e6)];
      if (row.group_n.empty()) {
        row.distance_m = samples[i].distance_m;
        row.group_n.assign(groups, 0);
        row.group_beyond.assign(groups, 0);
        row.group_mean_error_m.assign(groups, 0.0);
      }
      // corrected − truth = (Z − b̂) − D = (Z − D) − b̂ = −(held-out error).
      const double error_m = -cv.errors_m[i];
      const double std_m = i < cv.std_m.size() ? cv.std_m[i] : std::nan("");
      const bool beyond = error_m > k * std_m;
      ++row.n;
      row.beyond += beyond;
      row.mean_error_m += error_m;
      row.mean_std_m += std_m;
      row.rms_z += (error_m / std_m) * (error_m / std_m);
      ++row.group_n[g];
      row.group_beyond[g] += beyond;
      row.group_mean_error_m[g] += error_m;
    }
  }
  std::vector<CoverageRow> out;
  for (auto& [key, row] : rows) {
    row.mean_error_m /= row.n;
    row.mean_std_m /= row.n;
    row.rms_z = std::sqrt(row.rms_z / row.n);
    row.promise_p = BinomialUpperTail(row.n, row.beyond, 0.5 * std::erfc(k / std::sqrt(2.0)));
    for (size_t g = 0; g < groups; ++g)
      if (row.group_n[g] > 0) row.group_mean_error_m[g] /= row.group_n[g];
    out.push_back(row);
  }
  return out;
}

std::string FormatCoverageTable(const FitReport& report, double k) {
  std::string out;
  const size_t schemes = report.groups.empty() ? 0 : report.groups[0].cv.size();
  for (size_t s = 0; s < schemes; ++s) out += FormatCoverageTable(report, k, s);
  if (schemes == 0) out = "coverage: no cross-validation was run\n";
  return out;
}

std::string FormatCoverageTable(const FitReport& report, double k, size_t scheme) {
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "coverage of corrected - %g*sigma, held out (%s): share of truths beyond it\n",
                k, CvSchemeName(report.groups[0].cv[scheme].scheme).c_str());
  std::string out = buf;
  std::snprintf(buf, sizeof(buf), "%10s %4s %8s %7s %9s %12s %10s %6s", "distance_m", "n",
                "beyond", "share", "p_promise", "mean_err_m", "mean_std_m", "rms_z");
  out += buf;
  for (const auto& g : report.groups) {
    std::snprintf(buf, sizeof(buf), " %18s", (g.group.Label() + " b/n err").c_str());
    out += buf;
  }
  out += "\n";
  for (const CoverageRow& r : Coverage(report, k, scheme)) {
    std::snprintf(buf, sizeof(buf), "%10g %4d %8d %6.1f%% %9.2f %+12.3f %10.3f %6.2f",
                  r.distance_m, r.n, r.beyond, 100.0 * r.beyond / std::max(1, r.n), r.promise_p,
                  r.mean_error_m, r.mean_std_m, r.rms_z);
    out += buf;
    for (size_t g = 0; g < r.group_n.size(); ++g) {
      std::snprintf(buf, sizeof(buf), " %9d/%-2d %+6.3f", r.group_beyond[g], r.group_n[g],
                    r.group_mean_error_m[g]);
      out += buf;
    }
    out += "\n";
  }
  std::snprintf(buf, sizeof(buf),
                "p_promise: chance of at least that many truths beyond if each had exactly the "
                "normal promise %.2f%%; rms_z: rms of (corrected - truth)/sigma, 1 when sigma is "
                "the right size\n",
                50.0 * std::erfc(k / std::sqrt(2.0)));
  out += buf;
  return out;
}

records::BiasWeights ToWeights(const FitReport& report, const FitGroupsParams& params) {
  records::BiasWeights w;
  const FitParams& fit = report.fitted;
  w.model = fit.model;
  w.lambda = fit.lambda;
  w.loss = LossName(ResolveLoss(fit.loss, fit.model));
  w.loss_scale_m = fit.loss_scale_m;
  w.focal_px = fit.focal_px;
  w.baseline_m = fit.baseline_m;
  w.group_by = params.group_by;
  if (params.fit.margins.enabled) {
    w.near_m = params.fit.margins.guard.near_m;
    w.full_m = params.fit.margins.guard.full_m;
    w.noise_pooled = params.fit.margins.residual.pool_noise;
  }
  for (const auto& gr : report.groups) {
    records::BiasWeightsGroup g;
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
    if (gr.fit.residual_model.known) {
      g.margin.known = true;
      g.margin.placement_m = gr.fit.residual_model.placement_m;
      g.margin.noise_per_m = gr.fit.residual_model.noise_per_m;
      g.margin.weighted = gr.fit.margin_weighted;
      g.margin.errors = gr.fit.margin_in_sample ? "in_sample" : "held_out";
    }
    g.disparity_noise = gr.disparity_noise;
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
