#include "model/cv.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace depthbias::model {
namespace {

std::vector<Sample> Subset(const std::vector<Sample>& samples, const std::vector<int>& folds,
                           int fold, bool in) {
  std::vector<Sample> out;
  for (size_t i = 0; i < samples.size(); ++i) {
    if ((folds[i] == fold) == in) out.push_back(samples[i]);
  }
  return out;
}

void Summarize(CvResult* r) {
  double s2 = 0.0, sa = 0.0;
  for (double e : r->errors_m) {
    s2 += e * e;
    sa += std::abs(e);
  }
  const double n = static_cast<double>(r->errors_m.size());
  r->rmse_m = std::sqrt(s2 / n);
  r->mae_m = sa / n;
}

}  // namespace

bool ParseCvScheme(const std::string& text, CvScheme* scheme) {
  if (text == "none") *scheme = CvScheme::kNone;
  else if (text == "point") *scheme = CvScheme::kPoint;
  else if (text == "distance") *scheme = CvScheme::kDistance;
  else if (text == "angle") *scheme = CvScheme::kAngle;
  else return false;
  return true;
}

std::string CvSchemeName(CvScheme scheme) {
  switch (scheme) {
    case CvScheme::kPoint: return "point";
    case CvScheme::kDistance: return "distance";
    case CvScheme::kAngle: return "angle";
    default: return "none";
  }
}

std::vector<int> FoldIds(const std::vector<Sample>& samples, CvScheme scheme) {
  std::map<std::pair<long long, long long>, int> keys;
  auto key = [scheme](const Sample& s) {
    const long long d = scheme == CvScheme::kAngle ? 0 : std::llround(s.distance_m * 1e6);
    const long long a = scheme == CvScheme::kDistance ? 0 : std::llround(s.angle_deg * 1e6);
    return std::make_pair(d, a);
  };
  for (const auto& s : samples) keys.emplace(key(s), 0);
  int next = 0;
  for (auto& [k, id] : keys) id = next++;
  std::vector<int> ids;
  for (const auto& s : samples) ids.push_back(keys.at(key(s)));
  return ids;
}

CvResult CrossValidateFolds(
    const std::vector<Sample>& samples, CvScheme scheme,
    const std::function<FitResult(int fold, const std::vector<Sample>& train)>& fit_fold) {
  CvResult r;
  r.scheme = scheme;
  if (scheme == CvScheme::kNone) {
    r.message = "no cross-validation asked";
    return r;
  }
  const auto folds = FoldIds(samples, scheme);
  r.folds = folds.empty() ? 0 : *std::max_element(folds.begin(), folds.end()) + 1;
  if (r.folds < 2) {
    r.message = "cross-validation needs at least two folds, the rows give " +
                std::to_string(r.folds);
    return r;
  }
  r.errors_m.assign(samples.size(), std::numeric_limits<double>::quiet_NaN());
  r.std_m.assign(samples.size(), std::numeric_limits<double>::quiet_NaN());
  for (int f = 0; f < r.folds; ++f) {
    const FitResult fit = fit_fold(f, Subset(samples, folds, f, false));
    if (!fit.success) {
      r.message = "fold " + std::to_string(f) + ": " + fit.message;
      return r;
    }
    for (size_t i = 0; i < samples.size(); ++i) {
      if (folds[i] != f) continue;
      r.errors_m[i] = PredictBias(fit, samples[i].x) - samples[i].target_m;
      r.std_m[i] = PredictiveStd(fit, samples[i].x);
    }
  }
  Summarize(&r);
  r.success = std::isfinite(r.rmse_m);
  if (!r.success) r.message = "a held-out prediction is not finite";
  return r;
}

CvResult CrossValidate(const std::vector<Sample>& samples, const FitParams& params,
                       CvScheme scheme) {
  // With covariance: the held-out predictive σ.
  return CrossValidateFolds(samples, scheme, [&](int, const std::vector<Sample>& train) {
    return Fit(train, params);
  });
}

CvResult NestedCrossValidate(const std::vector<Sample>& samples,
                             const std::vector<FitParams>& candidates, CvScheme scheme,
                             std::vector<int>* chosen) {
  if (chosen) chosen->clear();
  if (candidates.empty()) {
    CvResult r;
    r.scheme = scheme;
    r.message = "nested cross-validation needs a scheme, two folds and a candidate";
    return r;
  }
  return CrossValidateFolds(samples, scheme, [&](int, const std::vector<Sample>& train) {
    int best = -1;
    double best_rmse = std::numeric_limits<double>::infinity();
    for (size_t c = 0; c < candidates.size(); ++c) {
      const CvResult inner = CrossValidate(train, candidates[c], scheme);
      if (inner.success && inner.rmse_m < best_rmse) {
        best_rmse = inner.rmse_m;
        best = static_cast<int>(c);
      }
    }
    FitResult fit;
    if (best < 0) {
      fit.message = "no candidate could be cross-validated";
      return fit;
    }
    FitParams p = candidates[static_cast<size_t>(best)];
    p.compute_covariance = false;
    fit = Fit(train, p);
    if (fit.success && chosen) chosen->push_back(best);
    return fit;
  });
}

}  // namespace depthbias::model
