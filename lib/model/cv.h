#pragma once
// Cross-validation of a bias fit on one group's samples:
//  - point: leave one test point out; a test point is a (distance, angle) pair, so the
//    emitter-on and emitter-off rows of a point leave together;
//  - distance: leave one distance out (every row at that distance);
//  - angle: leave one off-axis angle out (every row at that angle): a per-placement error that a
//    per-angle parameter absorbs in-sample shows up here, and a margin must hold for an angle it
//    has not seen.
// Each fold refits with the same parameters on the rest and predicts the held-out rows.

#include <functional>
#include <string>
#include <vector>

#include "model/fit.h"

namespace depthbias::model {

enum class CvScheme { kNone, kPoint, kDistance, kAngle };
bool ParseCvScheme(const std::string& text, CvScheme* scheme);
std::string CvSchemeName(CvScheme scheme);

// Fold index of every sample (0-based, folds in ascending key order).
std::vector<int> FoldIds(const std::vector<Sample>& samples, CvScheme scheme);

struct CvResult {
  CvScheme scheme = CvScheme::kNone;
  bool success = false;
  std::string message;       // why not (the first failed fold), when !success
  int folds = 0;
  double rmse_m = 0.0;       // of held-out errors, unweighted
  double mae_m = 0.0;
  std::vector<double> errors_m;  // predicted − target, per sample (held out)
  std::vector<double> std_m;     // held-out predictive σ per sample
  std::vector<int> chosen;       // candidate chosen in each fold, when the fit is a choice
};

// The loop every cross-validation shares: for each fold of `scheme`, fit_fold(fold, training
// rows) gives the fit that predicts the held-out rows (its guarded bias and predictive σ); a
// failed fit ends it with "fold f: <its message>". Fills errors_m, std_m, rmse_m, mae_m.
CvResult CrossValidateFolds(
    const std::vector<Sample>& samples, CvScheme scheme,
    const std::function<FitResult(int fold, const std::vector<Sample>& train)>& fit_fold);

CvResult CrossValidate(const std::vector<Sample>& samples, const FitParams& params,
                       CvScheme scheme);

// Honest estimate of "choose the form by cross-validation, then fit": in every outer fold the
// candidate with the lowest inner cross-validated RMSE (same scheme, on the outer training
// rows only) is chosen and refitted, then predicts the held-out rows. `chosen` gets the index
// of the candidate each outer fold picked.
CvResult NestedCrossValidate(const std::vector<Sample>& samples,
                             const std::vector<FitParams>& candidates, CvScheme scheme,
                             std::vector<int>* chosen = nullptr);

}  // namespace depthbias::model
