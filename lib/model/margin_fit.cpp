#include "model/margin_fit.h"

#include "model/select.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace depthbias::model {
namespace {

std::vector<Sample> Weighted(std::vector<Sample> samples, const std::vector<double>& w) {
  for (size_t i = 0; i < samples.size(); ++i) samples[i].weight = w[i];
  return samples;
}

// In-sample guarded residuals scaled by n/(n − p): the fallback when test points cannot be left
// out (a design with one row at some angle).
std::vector<double> InSampleErrors(const std::vector<Sample>& samples, const FitResult& fit,
                                   const NearGuard& guard) {
  const double n = static_cast<double>(samples.size());
  const double p = static_cast<double>(fit.values.size());
  const double scale = n > p ? std::sqrt(n / (n - p)) : 1.0;
  std::vector<double> e;
  for (const auto& s : samples) {
    const double b = fit.form->Bias(fit.values.data(), s.x);
    e.push_back(scale * (GuardedBias(b, s.x, guard) - s.target_m));
  }
  return e;
}

// The covariance of a fit with weights w when row i has variance σ²(Z_i): the sandwich
// C·(Σ w_i² σ_i² g_i g_iᵀ)·C with C the inverse of the weighted normal matrix (prior included).
// With w_i ∝ 1/σ_i² this is C / mean(1/σ²): the usual weighted least-squares covariance.
void SandwichCovariance(const std::vector<Sample>& samples, const ResidualModel& model,
                        FitResult* fit) {
  if (!fit->covariance_ok || !(fit->residual_std_m > 0.0)) return;
  const Eigen::MatrixXd c = fit->covariance / (fit->residual_std_m * fit->residual_std_m);
  const auto p = static_cast<Eigen::Index>(fit->values.size());
  Eigen::MatrixXd meat = Eigen::MatrixXd::Zero(p, p);
  for (const auto& s : samples) {
    const auto g = fit->form->BiasGradient(fit->values.data(), s.x);
    const Eigen::Map<const Eigen::VectorXd> gv(g.data(), p);
    meat += s.weight * s.weight * model.VarianceM2(s.x.depth_m) * gv * gv.transpose();
  }
  fit->covariance = c * meat * c;
}

}  // namespace

JointFitResult FitWithMargins(const std::vector<std::vector<Sample>>& scenarios,
                              const FitParams& params, const std::vector<ResidualData>& fixed) {
  JointFitResult r;
  std::string why;
  if (!params.IsValid(&why)) {
    r.message = why;
    return r;
  }
  const size_t n = scenarios.size();
  r.fits.resize(n);
  if (!params.margins.enabled) {
    for (size_t g = 0; g < n; ++g) {
      r.fits[g] = Fit(scenarios[g], params);
      if (!r.fits[g].success) {
        r.message = "scenario " + std::to_string(g) + ": " + r.fits[g].message;
        return r;
      }
    }
    r.success = true;
    return r;
  }
  const bool weighted = params.margins.Weighted(params.model);
  const int rounds = weighted ? params.margins.rounds : 1;
  std::vector<std::vector<double>> prior(n), w(n);
  for (size_t g = 0; g < n; ++g) {
    for (const auto& s : scenarios[g]) prior[g].push_back(s.weight);
    w[g] = prior[g];
  }
  FitParams plain = params;
  r.errors.assign(n, {});
  std::vector<std::string> fallback(n);  // why scenario g's errors are in-sample ("" if not)
  for (int round = 0; round <= rounds; ++round) {
    const bool last = round == rounds;
    for (size_t g = 0; g < n; ++g) {
      const auto samples = Weighted(scenarios[g], w[g]);
      FitParams p = plain;
      p.compute_covariance = last && params.compute_covariance;
      r.fits[g] = Fit(samples, p);
      if (!r.fits[g].success) {
        r.message = "scenario " + std::to_string(g) + ": " + r.fits[g].message;
        return r;
      }
      if (last) continue;
      std::vector<double> e;
      if (PointHeldOutErrors(samples, params, &e, &why)) {
        fallback[g].clear();
      } else {
        // Said, never silent: the margin then rests on in-sample residuals (scaled by n/(n − p)).
        fallback[g] = why;
        e = InSampleErrors(samples, r.fits[g], params.margins.guard);
      }
      ResidualData& d = r.errors[g];
      d.depth_m.clear();
      d.error2_m2.clear();
      for (size_t i = 0; i < samples.size(); ++i) {
        d.depth_m.push_back(samples[i].x.depth_m);
        d.error2_m2.push_back(e[i] * e[i]);
      }
    }
    if (last) break;
    std::vector<ResidualData> all = r.errors;
    all.insert(all.end(), fixed.begin(), fixed.end());
    r.residual = FitResidualModel(all, params.margins.residual);
    if (!r.residual.success) {
      r.message = r.residual.message;
      return r;
    }
    if (!weighted) {
      w = prior;
      continue;  // one more (final) fit with the prior weights
    }
    for (size_t g = 0; g < n; ++g) {
      double mean = 0.0;
      for (size_t i = 0; i < w[g].size(); ++i) {
        w[g][i] = prior[g][i] / r.residual.models[g].VarianceM2(scenarios[g][i].x.depth_m);
        mean += w[g][i];
      }
      mean /= static_cast<double>(w[g].size());
      for (double& x : w[g]) x = mean > 0.0 ? x / mean : 1.0;
    }
  }
  for (size_t g = 0; g < n; ++g) {
    FitResult& f = r.fits[g];
    f.residual_model = r.residual.models[g];
    f.guard = params.margins.guard;
    f.margin_weighted = weighted;
    if (!fallback[g].empty()) {
      f.margin_in_sample = true;
      f.margin_note = "sigma fitted to in-sample residuals: no held-out errors (" + fallback[g] +
                      ")";
      r.warnings.push_back("scenario " + std::to_string(g) + ": " + f.margin_note);
    }
    SandwichCovariance(Weighted(scenarios[g], w[g]), f.residual_model, &f);
  }
  r.success = true;
  return r;
}

CvResult CrossValidateWithMargins(const std::vector<Sample>& samples, const FitParams& params,
                                  CvScheme scheme, const std::vector<ResidualData>& fixed) {
  return CrossValidateFolds(samples, scheme, [&](int, const std::vector<Sample>& train) {
    JointFitResult joint = FitWithMargins({train}, params, fixed);
    if (joint.success) return joint.fits[0];
    FitResult failed;
    failed.message = joint.message;
    return failed;
  });
}

}  // namespace depthbias::model
