#pragma once
// Bias model forms: each predicts the bias b = measured median depth − nominal distance [m]
// of a target seen at measured depth Z [m] and off-axis angle α [rad], from a parameter
// vector θ. The forms only compute; fitting is in fit.h, cross-validation in cv.h.
// README.md beside this file documents every parameter (unit and physical meaning).

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "camera/intrinsics.h"

namespace depthbias::model {

// One sample as the forms see it.
struct Features {
  double depth_m = 0.0;    // Z: measured median depth
  double angle_rad = 0.0;  // α: off-axis angle of the target
};

struct ParamSpec {
  std::string name;
  std::string unit;
  double initial = 0.0;     // starting value of the fit
  double prior_mean = 0.0;  // mean of the L2 prior (the physically neutral value)
  bool penalized = true;    // false: free of the prior by default (paper6's intercept)
};

// Constants a form may need (from config: D455 defaults, or the recording).
struct FormConstants {
  double focal_px = camera::D455::kFocalPx;     // f: depth focal length [px]
  double baseline_m = camera::D455::kBaselineM;  // B: stereo baseline [m]
  std::vector<double> knots_deg;  // off-axis knots of "disp_knots", ascending
};

class Form {
 public:
  virtual ~Form() = default;
  virtual std::string name() const = 0;
  virtual const std::vector<ParamSpec>& params() const = 0;
  int num_params() const { return static_cast<int>(params().size()); }
  // Predicted bias [m].
  virtual double Bias(const double* theta, const Features& x) const = 0;
  // ∂bias/∂θ at x (size num_params()).
  virtual std::vector<double> BiasGradient(const double* theta, const Features& x) const = 0;
  // The depth scale k(α) (true depth over the nominal range's projection) of a disparity-space
  // form at α; NaN for a form without one (paper6).
  virtual double Scale(const double* /*theta*/, double /*angle_rad*/) const { return NAN; }
  // Fewest distinct distances and angles the form needs to be identifiable.
  virtual int min_distances() const = 0;
  virtual int min_angles() const = 0;
  const FormConstants& constants() const { return constants_; }

 protected:
  explicit Form(FormConstants c) : constants_(std::move(c)) {}
  FormConstants constants_;
};

// Names of the forms MakeForm knows, default first.
const std::vector<std::string>& FormNames();
// Builds a form by name; throws std::invalid_argument naming the unknown model and the known
// ones. "disp_knots" needs constants.knots_deg (at least one knot).
std::unique_ptr<Form> MakeForm(const std::string& name, const FormConstants& constants);

// The forms' equations, templated so Ceres can differentiate them (forms.cpp wraps them).
namespace eq {

// eq. 6 of the article: b = w0 + w1·Z + w2·Z² + w3·tanα + w4·tan²α + w5·Z·tanα.
template <typename T>
T Paper6(const T* w, double z, double alpha) {
  const double t = std::tan(alpha);
  return w[0] + w[1] * z + w[2] * z * z + w[3] * t + w[4] * t * t + w[5] * z * t;
}

// Disparity-space forward model (DESIGN.md: d = f·B/Z):
//   true depth of the target   Z_t = k(α) · D · cos α        (range → depth, scale k)
//   measured disparity         d_m = f·B / Z_t + δ           (disparity offset δ)
// so, given the measured Z = f·B / d_m, the nominal distance is
//   D̂ = Z_t / (k(α)·cos α),  Z_t = 1 / (1/Z − δ/(f·B)),
// and the bias is b = Z − D̂. For small δ: Z − Z_t ≈ −δ·Z²/(f·B).
template <typename T>
T DisparityBias(const T& delta_px, const T& k, double z, double alpha, double fb_pxm) {
  const T true_depth = 1.0 / (1.0 / z - delta_px / fb_pxm);
  return z - true_depth / (k * std::cos(alpha));
}

// k(α) = k0 + k1·tanα + k2·tan²α.
template <typename T>
T TanScale(const T* k, double alpha) {
  const double t = std::tan(alpha);
  return k[0] + k[1] * t + k[2] * t * t;
}

// k(α) piecewise linear in α between knots, constant beyond the first and last knot.
template <typename T>
T KnotScale(const T* k, const std::vector<double>& knots_rad, double alpha) {
  const size_t n = knots_rad.size();
  if (n == 1 || alpha <= knots_rad.front()) return k[0];
  if (alpha >= knots_rad.back()) return k[n - 1];
  size_t i = 1;
  while (knots_rad[i] < alpha) ++i;
  const double u = (alpha - knots_rad[i - 1]) / (knots_rad[i] - knots_rad[i - 1]);
  return (1.0 - u) * k[i - 1] + u * k[i];
}

}  // namespace eq
}  // namespace depthbias::model
