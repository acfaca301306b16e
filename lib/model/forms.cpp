#include "model/forms.h"

#include <cstdio>
#include <stdexcept>

#include <ceres/jet.h>

namespace depthbias::model {
namespace {

constexpr int kMaxParams = 24;  // Jet size for the gradients; forms have far fewer
constexpr double kDegToRad = M_PI / 180.0;

// Value and gradient of a form's templated Eval, by forward-mode automatic differentiation.
template <class F>
class FormImpl : public Form {
 public:
  using Form::Form;
  double Bias(const double* theta, const Features& x) const override {
    return static_cast<const F*>(this)->Eval(theta, x.depth_m, x.angle_rad);
  }
  std::vector<double> BiasGradient(const double* theta, const Features& x) const override {
    using Jet = ceres::Jet<double, kMaxParams>;
    const int n = num_params();
    std::vector<Jet> t(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) t[static_cast<size_t>(i)] = Jet(theta[i], i);
    const Jet b = static_cast<const F*>(this)->Eval(t.data(), x.depth_m, x.angle_rad);
    std::vector<double> g(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) g[static_cast<size_t>(i)] = b.v[i];
    return g;
  }
  const std::vector<ParamSpec>& params() const override { return params_; }

 protected:
  std::vector<ParamSpec> params_;
};

class Paper6Form : public FormImpl<Paper6Form> {
 public:
  explicit Paper6Form(const FormConstants& c) : FormImpl(c) {
    params_ = {{"w0", "m", 0, 0, false},     {"w1", "m/m", 0, 0, true},
               {"w2", "m/m^2", 0, 0, true},  {"w3", "m", 0, 0, true},
               {"w4", "m", 0, 0, true},      {"w5", "m/m", 0, 0, true}};
  }
  std::string name() const override { return "paper6"; }
  int min_distances() const override { return 3; }
  int min_angles() const override { return 3; }
  template <typename T>
  T Eval(const T* w, double z, double a) const { return eq::Paper6(w, z, a); }
};

double FocalBaseline(const FormConstants& c) { return c.focal_px * c.baseline_m; }

class DispScaleForm : public FormImpl<DispScaleForm> {
 public:
  explicit DispScaleForm(const FormConstants& c) : FormImpl(c) {
    params_ = {{"delta_px", "px", 0, 0, true}, {"k", "1", 1, 1, true}};
  }
  std::string name() const override { return "disp_scale"; }
  double Scale(const double* p, double) const override { return p[1]; }
  int min_distances() const override { return 2; }
  int min_angles() const override { return 1; }
  template <typename T>
  T Eval(const T* p, double z, double a) const {
    return eq::DisparityBias(p[0], p[1], z, a, FocalBaseline(constants_));
  }
};

class DispTanForm : public FormImpl<DispTanForm> {
 public:
  explicit DispTanForm(const FormConstants& c) : FormImpl(c) {
    params_ = {{"delta_px", "px", 0, 0, true},
               {"k0", "1", 1, 1, true},
               {"k1", "1", 0, 0, true},
               {"k2", "1", 0, 0, true}};
  }
  std::string name() const override { return "disp_tan"; }
  double Scale(const double* p, double a) const override { return eq::TanScale(p + 1, a); }
  int min_distances() const override { return 2; }
  int min_angles() const override { return 3; }
  template <typename T>
  T Eval(const T* p, double z, double a) const {
    return eq::DisparityBias(p[0], eq::TanScale(p + 1, a), z, a, FocalBaseline(constants_));
  }
};

std::string KnotName(double deg) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "k_%gdeg", deg);
  return buf;
}

class DispKnotsForm : public FormImpl<DispKnotsForm> {
 public:
  explicit DispKnotsForm(const FormConstants& c) : FormImpl(c) {
    if (c.knots_deg.empty()) throw std::invalid_argument("disp_knots needs at least one knot");
    if (static_cast<int>(c.knots_deg.size()) + 1 > kMaxParams) {
      throw std::invalid_argument("disp_knots: too many off-axis knots (" +
                                  std::to_string(c.knots_deg.size()) + ")");
    }
    params_ = {{"delta_px", "px", 0, 0, true}};
    for (size_t i = 0; i < c.knots_deg.size(); ++i) {
      if (i > 0 && !(c.knots_deg[i] > c.knots_deg[i - 1])) {
        throw std::invalid_argument("disp_knots: knots must be strictly ascending");
      }
      knots_rad_.push_back(c.knots_deg[i] * kDegToRad);
      params_.push_back({KnotName(c.knots_deg[i]), "1", 1, 1, true});
    }
  }
  std::string name() const override { return "disp_knots"; }
  double Scale(const double* p, double a) const override {
    return eq::KnotScale(p + 1, knots_rad_, a);
  }
  int min_distances() const override { return 2; }
  int min_angles() const override { return 1; }
  template <typename T>
  T Eval(const T* p, double z, double a) const {
    return eq::DisparityBias(p[0], eq::KnotScale(p + 1, knots_rad_, a), z, a,
                             FocalBaseline(constants_));
  }

 private:
  std::vector<double> knots_rad_;
};

}  // namespace

const std::vector<std::string>& FormNames() {
  static const std::vector<std::string> names = {"disp_knots", "disp_tan", "disp_scale",
                                                 "paper6"};
  return names;
}

std::unique_ptr<Form> MakeForm(const std::string& name, const FormConstants& constants) {
  if (name == "paper6") return std::make_unique<Paper6Form>(constants);
  if (!(constants.focal_px > 0.0) || !(constants.baseline_m > 0.0)) {
    throw std::invalid_argument("model '" + name + "' needs focal_px > 0 and baseline_m > 0");
  }
  if (name == "disp_scale") return std::make_unique<DispScaleForm>(constants);
  if (name == "disp_tan") return std::make_unique<DispTanForm>(constants);
  if (name == "disp_knots") return std::make_unique<DispKnotsForm>(constants);
  std::string known;
  for (const auto& n : FormNames()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown model '" + name + "' (known: " + known + ")");
}

}  // namespace depthbias::model
