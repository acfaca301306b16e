#include "model/select.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/margin_fit.h"

namespace depthbias::model {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

double SumSquares(const std::vector<double>& e) {
  double s = 0.0;
  for (double x : e) s += x * x;
  return s;
}

}  // namespace

std::vector<FitParams> SelectionCandidates(const FitParams& base) {
  std::vector<FitParams> out;
  for (const auto& name : FormNames()) {
    for (Loss loss : {Loss::kHuber, Loss::kNone}) {
      FitParams p = base;
      p.model = name;
      p.loss = loss;
      p.priors.clear();
      p.margins.weighting = MarginParams::Weighting::kOff;  // the point fit: metres, unweighted
      out.push_back(p);
    }
  }
  return out;
}

bool PointHeldOutErrors(const std::vector<Sample>& samples, const FitParams& params,
                        std::vector<double>* errors, std::string* why) {
  FitParams p = params;
  p.compute_covariance = false;
  const NearGuard guard = params.margins.enabled ? params.margins.guard : NearGuard{};
  const auto folds = FoldIds(samples, CvScheme::kPoint);
  const int n_folds = folds.empty() ? 0 : *std::max_element(folds.begin(), folds.end()) + 1;
  if (n_folds < 2) {
    *why = "fewer than two test points";
    return false;
  }
  errors->assign(samples.size(), kNan);
  for (int f = 0; f < n_folds; ++f) {
    std::vector<Sample> train;
    for (size_t i = 0; i < samples.size(); ++i)
      if (folds[i] != f) train.push_back(samples[i]);
    const FitResult fit = Fit(train, p);
    if (!fit.success) {
      *why = "leaving out test point " + std::to_string(f) + ": " + fit.message;
      return false;
    }
    for (size_t i = 0; i < samples.size(); ++i) {
      if (folds[i] != f) continue;
      const double b = fit.form->Bias(fit.values.data(), samples[i].x);
      (*errors)[i] = GuardedBias(b, samples[i].x, guard) - samples[i].target_m;
    }
  }
  return true;
}

Selector::Selector(std::vector<std::vector<Sample>> scenarios, std::vector<FitParams> candidates)
    : scenarios_(std::move(scenarios)), candidates_(std::move(candidates)) {}

std::string Selector::Label(int c) const {
  const FitParams& p = candidates_.at(static_cast<size_t>(c));
  return p.model + "/" + LossName(ResolveLoss(p.loss, p.model));
}

bool Selector::Whole(size_t c, size_t g, double* sse, std::string* why) {
  auto it = whole_.find({c, g});
  if (it == whole_.end()) {
    std::vector<double> e;
    std::string w;
    const bool ok = PointHeldOutErrors(scenarios_[g], candidates_[c], &e, &w);
    const double s = ok ? SumSquares(e) : kNan;
    it = whole_.emplace(std::make_pair(c, g), std::make_pair(std::isfinite(s) ? s : kNan,
                                                             ok ? "not finite" : w)).first;
  }
  *sse = it->second.first;
  if (why) *why = it->second.second;
  return std::isfinite(*sse);
}

int Selector::Choose(int group, const std::vector<Sample>* train, std::string* why) {
  int best = -1;
  double best_sse = std::numeric_limits<double>::infinity();
  std::string last_why = "no candidate";
  for (size_t c = 0; c < candidates_.size(); ++c) {
    double total = 0.0;
    bool ok = true;
    for (size_t g = 0; g < scenarios_.size() && ok; ++g) {
      double sse = 0.0;
      std::string w;
      if (train != nullptr && static_cast<int>(g) == group) {
        std::vector<double> e;
        ok = PointHeldOutErrors(*train, candidates_[c], &e, &w);
        sse = ok ? SumSquares(e) : kNan;
        ok = ok && std::isfinite(sse);
      } else {
        ok = Whole(c, g, &sse, &w);
      }
      if (!ok) last_why = Label(static_cast<int>(c)) + ": " + w;
      total += sse;
    }
    if (ok && total < best_sse) {
      best_sse = total;
      best = static_cast<int>(c);
    }
  }
  if (best < 0 && why) *why = "no candidate could be cross-validated (" + last_why + ")";
  return best;
}

std::vector<double> Selector::PooledRmse() {
  std::vector<double> out;
  for (size_t c = 0; c < candidates_.size(); ++c) {
    double total = 0.0, n = 0.0;
    for (size_t g = 0; g < scenarios_.size(); ++g) {
      double sse = 0.0;
      if (!Whole(c, g, &sse, nullptr)) total = kNan;
      total += sse;
      n += static_cast<double>(scenarios_[g].size());
    }
    out.push_back(n > 0 ? std::sqrt(total / n) : kNan);
  }
  return out;
}

CvResult CrossValidateSelected(Selector* selector, int group, CvScheme scheme,
                               const std::function<std::vector<ResidualData>(int)>& fixed_for) {
  std::vector<int> chosen;
  CvResult r = CrossValidateFolds(
      selector->scenarios().at(static_cast<size_t>(group)), scheme,
      [&](int, const std::vector<Sample>& train) {
        FitResult fit;
        const int c = selector->Choose(group, &train, &fit.message);
        if (c < 0) return fit;
        chosen.push_back(c);
        const JointFitResult joint =
            FitWithMargins({train}, selector->candidates()[static_cast<size_t>(c)], fixed_for(c));
        if (joint.success) return joint.fits[0];
        fit.message = joint.message;
        return fit;
      });
  r.chosen = chosen;
  return r;
}

}  // namespace depthbias::model
