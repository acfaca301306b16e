#pragma once
// The point fit, chosen by cross-validated RMSE in metres (the article's measure). The
// correction and its σ are two layers: the point fit is the candidate (form and loss) whose
// guarded held-out errors — leave one test point out, in metres, pooled over every scenario of
// the unit (one camera, one form) — are smallest; σ is then fitted to the held-out errors of the
// point fit chosen (margin_fit.h).
//
// A choice made on the data must be judged on rows it did not see: CrossValidateSelected makes
// the choice again inside every outer fold, on that fold's training rows only (the held-out
// scenario's rows minus the fold, the other scenarios whole), then fits the chosen candidate with
// its margin and predicts the held-out rows.

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "model/cv.h"
#include "model/fit.h"
#include "model/margin.h"

namespace depthbias::model {

// Every form with its default loss and with the other of {none, huber}, unweighted point fits,
// the other settings of `base`.
std::vector<FitParams> SelectionCandidates(const FitParams& base);

// Guarded held-out errors (predicted − target) of a candidate, leaving one test point out.
// False (with why) when a fold cannot be fitted.
bool PointHeldOutErrors(const std::vector<Sample>& samples, const FitParams& params,
                        std::vector<double>* errors, std::string* why);

class Selector {
 public:
  // The scenarios of one unit (every row the choice may see) and the candidates.
  Selector(std::vector<std::vector<Sample>> scenarios, std::vector<FitParams> candidates);

  // The candidate with the lowest pooled held-out RMSE; when `train` is given it replaces the
  // rows of scenario `group` (an outer fold's training rows). -1 when no candidate could be
  // cross-validated everywhere (*why says why).
  int Choose(int group = -1, const std::vector<Sample>* train = nullptr,
             std::string* why = nullptr);
  // Pooled held-out RMSE of each candidate on the whole unit (NaN where it could not be run).
  std::vector<double> PooledRmse();
  const std::vector<FitParams>& candidates() const { return candidates_; }
  const std::vector<std::vector<Sample>>& scenarios() const { return scenarios_; }
  // "disp_tan/huber"
  std::string Label(int c) const;

 private:
  // Σ e² and n of candidate c on scenario g's whole rows (cached).
  bool Whole(size_t c, size_t g, double* sse, std::string* why);
  std::vector<std::vector<Sample>> scenarios_;
  std::vector<FitParams> candidates_;
  std::map<std::pair<size_t, size_t>, std::pair<double, std::string>> whole_;  // NaN: failed
};

// Cross-validation of "choose, then fit with margins" on scenario `group` of the selector's unit.
// `fixed_for(c)` gives the other scenarios' residual data under candidate c (the pooled noise
// term). CvResult::chosen gets the candidate each fold chose.
CvResult CrossValidateSelected(Selector* selector, int group, CvScheme scheme,
                               const std::function<std::vector<ResidualData>(int)>& fixed_for);

}  // namespace depthbias::model
