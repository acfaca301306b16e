#include "model/forms.h"

#include <gtest/gtest.h>

#include "model/fit.h"

namespace depthbias::model {
namespace {

FormConstants Constants() {
  FormConstants c;
  c.knots_deg = {0, 10, 20, 35};
  return c;
}

std::vector<double> Theta(const Form& f) {
  // A point away from the neutral values so every term matters.
  std::vector<double> t;
  for (int j = 0; j < f.num_params(); ++j) t.push_back(f.params()[j].initial + 0.1 * (j + 1));
  return t;
}

TEST(Forms, GradientsMatchCentralDifferences) {
  for (const auto& name : FormNames()) {
    const auto form = MakeForm(name, Constants());
    auto theta = Theta(*form);
    for (double z : {3.0, 9.5, 17.0}) {
      for (double a_deg : {0.0, 7.0, 20.0, 33.0}) {
        const Features x{z, a_deg * M_PI / 180.0};
        const auto g = form->BiasGradient(theta.data(), x);
        ASSERT_EQ(static_cast<int>(g.size()), form->num_params());
        for (int j = 0; j < form->num_params(); ++j) {
          const double h = 1e-6;
          auto tp = theta, tm = theta;
          tp[j] += h;
          tm[j] -= h;
          const double fd = (form->Bias(tp.data(), x) - form->Bias(tm.data(), x)) / (2 * h);
          EXPECT_NEAR(g[j], fd, 1e-6 * std::max(1.0, std::abs(fd)))
              << name << " param " << form->params()[j].name << " z " << z << " a " << a_deg;
        }
      }
    }
  }
}

TEST(Forms, Paper6IsEquationSix) {
  const auto f = MakeForm("paper6", {});
  const double w[6] = {0.5, -0.2, 0.01, 2.0, -5.0, 0.05};
  const double z = 7.0, a = 20.0 * M_PI / 180.0, t = std::tan(a);
  EXPECT_NEAR(f->Bias(w, {z, a}),
              0.5 - 0.2 * z + 0.01 * z * z + 2.0 * t - 5.0 * t * t + 0.05 * z * t, 1e-12);
}

TEST(Forms, DisparityOffsetGivesMinusDeltaZSquaredOverFB) {
  // At α = 0 and k = 1 the bias is Z − Z_t; for small δ, Z_t − Z ≈ δ·Z²/(f·B), so the bias of
  // measured minus true is ≈ −δ·Z²/(f·B) seen from the truth.
  const auto f = MakeForm("disp_scale", {});
  const double fb = 640.0 * 0.095;
  for (double z : {4.0, 8.0, 16.0}) {
    const double theta[2] = {0.01, 1.0};
    EXPECT_NEAR(f->Bias(theta, {z, 0.0}), -0.01 * z * z / fb, 5e-3 * 0.01 * z * z / fb) << z;
  }
}

TEST(Forms, RangeToDepthProjection) {
  // No offset, k = 1: the measured depth is the range times cos α, so the bias is −D(1 − cos α).
  const auto f = MakeForm("disp_scale", {});
  const double theta[2] = {0.0, 1.0};
  const double a = 35.0 * M_PI / 180.0, d = 8.0;
  EXPECT_NEAR(f->Bias(theta, {d * std::cos(a), a}), d * std::cos(a) - d, 1e-12);
}

TEST(Forms, KnotScaleInterpolatesAndClamps) {
  const auto f = MakeForm("disp_knots", Constants());
  const double theta[5] = {0.0, 1.0, 1.1, 1.2, 1.5};
  const double z = 10.0;
  auto k_of = [&](double deg) {
    const double a = deg * M_PI / 180.0;
    const double b = f->Bias(theta, {z, a});
    return z / ((z - b) * std::cos(a));  // D̂ = Z/(k cos α) with δ = 0
  };
  EXPECT_NEAR(k_of(0), 1.0, 1e-12);
  EXPECT_NEAR(k_of(15), 1.15, 1e-12);
  EXPECT_NEAR(k_of(27.5), 1.35, 1e-12);
  EXPECT_NEAR(k_of(40), 1.5, 1e-12);  // beyond the last knot: its value
}

TEST(Forms, UnknownModelIsNamed) {
  try {
    MakeForm("quadratic", {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("quadratic"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("paper6"), std::string::npos);
  }
  EXPECT_THROW(MakeForm("disp_knots", {}), std::invalid_argument);  // no knots
}

}  // namespace
}  // namespace depthbias::model
