#include "gap/calibrate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <map>
#include <sstream>

#include <ceres/ceres.h>

namespace depthbias::gap {
namespace {

constexpr double kLogitShift = 5.0;  // keeps logit p away from 0 for Ceres' relative steps

double Logit(double p) {
  p = std::clamp(p, 1e-6, 1 - 1e-6);
  return std::log(p / (1 - p));
}
double Logistic(double x) { return 1.0 / (1.0 + std::exp(-x)); }

// The recordings of one scenario, and the residuals of a candidate (log σ_d, logit p + shift).
class ScenarioResiduals {
 public:
  ScenarioResiduals(const sim::SimParams& base, std::vector<sim::Cell> cells,
                    std::vector<records::PanelMetrics> real, const CalibrateParams& cp)
      : base_(base), cells_(std::move(cells)), real_(std::move(real)), cp_(cp) {}

  int num_residuals() const { return 2 * static_cast<int>(cells_.size()); }

  static sim::ScenarioParams Decode(const double* x, const sim::ScenarioParams& like) {
    sim::ScenarioParams s = like;
    s.sigma_d_px = std::exp(x[0]);
    s.invalid_prob = Logistic(x[1] - kLogitShift);
    return s;
  }

  // Simulated metrics of every recording under scenario s.
  std::vector<records::PanelMetrics> Simulate(const sim::ScenarioParams& s) const {
    sim::SimParams p = base_;
    p.sensor.scenarios = {s};
    sim::MetricsParams mp = cp_.metrics;
    mp.frames = cp_.frames;
    std::vector<records::PanelMetrics> out;
    for (auto& r : sim::SimulateCellsMetrics(p, cells_, mp)) out.push_back(r.metrics);
    return out;
  }

  bool operator()(double const* const* x, double* residuals) const {
    const sim::ScenarioParams s = Decode(x[0], scenario_);
    if (!std::isfinite(s.sigma_d_px)) return false;
    const std::vector<records::PanelMetrics> sim = Simulate(s);
    for (size_t i = 0; i < cells_.size(); ++i) {
      const double real_std = real_[i].plane_std_m;
      const double sim_std = std::isfinite(sim[i].plane_std_m)
                                 ? std::max(sim[i].plane_std_m, 1e-6) : 1e-6;
      residuals[2 * i] =
          std::isfinite(real_std) && real_std > 0 ? std::log(sim_std / real_std) : 0.0;
      const double real_valid = real_[i].valid_pct;
      const double sim_valid = std::isfinite(sim[i].valid_pct) ? sim[i].valid_pct : 0.0;
      residuals[2 * i + 1] =
          std::isfinite(real_valid) ? (sim_valid - real_valid) / cp_.valid_scale_pct : 0.0;
    }
    return true;
  }

  void set_scenario(const sim::ScenarioParams& s) { scenario_ = s; }
  const std::vector<sim::Cell>& cells() const { return cells_; }
  const std::vector<records::PanelMetrics>& real() const { return real_; }

 private:
  sim::SimParams base_;
  std::vector<sim::Cell> cells_;
  std::vector<records::PanelMetrics> real_;
  CalibrateParams cp_;
  sim::ScenarioParams scenario_;
};

std::string Num(double v, int precision = 6) {
  std::ostringstream s;
  s << std::setprecision(precision) << v;
  return s.str();
}

}  // namespace

bool CalibrateParams::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (frames < 1) return fail("frames must be >= 1");
  if (!(valid_scale_pct > 0)) return fail("valid_scale_pct must be > 0");
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!(relative_step > 0 && relative_step < 0.5)) return fail("relative_step must be in (0, 0.5)");
  if (!(max_sigma_d_px > 1e-3)) return fail("max_sigma_d_px must be > 0.001");
  return metrics.IsValid(why);
}

CalibrationResult CalibrateSensor(const sim::SimParams& params,
                                  const std::vector<records::PanelMetrics>& real,
                                  const CalibrateParams& cp) {
  CalibrationResult result;
  result.sensor = params.sensor;
  std::string why;
  if (!cp.IsValid(&why) || !params.IsValid(&why)) {
    result.message = why;
    return result;
  }

  // Group the usable rows by scenario, in first-seen order.
  std::vector<std::pair<std::string, std::string>> order;
  std::map<std::pair<std::string, std::string>, std::pair<std::vector<sim::Cell>,
                                                          std::vector<records::PanelMetrics>>>
      groups;
  for (const auto& row : real) {
    const bool has_target = (std::isfinite(row.plane_std_m) && row.plane_std_m > 0) ||
                            std::isfinite(row.valid_pct);
    if (!row.ok() || !has_target || !std::isfinite(row.distance_m) ||
        !std::isfinite(row.angle_deg) || (row.emitter != "on" && row.emitter != "off")) {
      ++result.rows_skipped;
      continue;
    }
    sim::Cell c;
    c.distance_m = row.distance_m;
    c.angle_deg = row.angle_deg;
    c.preset = row.preset;
    c.emitter_on = row.emitter == "on";
    c.light = row.light;
    c.name = sim::CellName(c);
    const auto key = std::make_pair(row.light, row.preset);
    if (!groups.count(key)) order.push_back(key);
    groups[key].first.push_back(c);
    groups[key].second.push_back(row);
    ++result.rows_used;
  }
  if (order.empty()) {
    result.message = "no usable rows (status ok, emitter on/off, plane_std_m or valid_pct)";
    return result;
  }

  result.sensor.scenarios.clear();
  for (const auto& key : order) {
    auto& [cells, rows] = groups[key];
    ScenarioFit fit;
    fit.initial = params.sensor.Scenario(key.first, key.second);
    fit.recordings = static_cast<int>(cells.size());

    auto* functor = new ScenarioResiduals(params, cells, rows, cp);
    functor->set_scenario(fit.initial);
    ceres::NumericDiffOptions nd;
    nd.relative_step_size = cp.relative_step;
    auto* cost = new ceres::DynamicNumericDiffCostFunction<ScenarioResiduals, ceres::CENTRAL>(
        functor, ceres::TAKE_OWNERSHIP, nd);
    cost->AddParameterBlock(2);
    cost->SetNumResiduals(functor->num_residuals());
    double x[2] = {std::log(std::clamp(fit.initial.sigma_d_px, 1e-3, cp.max_sigma_d_px)),
                   Logit(fit.initial.invalid_prob) + kLogitShift};
    ceres::Problem problem;
    problem.AddResidualBlock(cost, nullptr, x);
    problem.SetParameterLowerBound(x, 0, std::log(1e-3));
    problem.SetParameterUpperBound(x, 0, std::log(cp.max_sigma_d_px));
    problem.SetParameterLowerBound(x, 1, kLogitShift - 12);
    problem.SetParameterUpperBound(x, 1, kLogitShift + 12);
    ceres::Solver::Options options;
    options.max_num_iterations = cp.max_iterations;
    options.linear_solver_type = ceres::DENSE_QR;
    options.logging_type = ceres::SILENT;
    options.function_tolerance = 1e-8;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);

    fit.fitted = ScenarioResiduals::Decode(x, fit.initial);
    fit.converged = summary.termination_type == ceres::CONVERGENCE;
    fit.iterations = static_cast<int>(summary.iterations.size());
    fit.initial_cost = summary.initial_cost;
    fit.final_cost = summary.final_cost;
    fit.report = summary.BriefReport();

    // The fitted simulation beside the real rows.
    const std::vector<records::PanelMetrics> sim = functor->Simulate(fit.fitted);
    double sum_log = 0, sum_valid = 0;
    int n_log = 0, n_valid = 0;
    for (size_t i = 0; i < cells.size(); ++i) {
      CalibrationCell c;
      c.bag = rows[i].bag;
      c.emitter = rows[i].emitter;
      c.distance_m = rows[i].distance_m;
      c.angle_deg = rows[i].angle_deg;
      c.real_plane_std_m = rows[i].plane_std_m;
      c.sim_plane_std_m = sim[i].plane_std_m;
      c.real_valid_pct = rows[i].valid_pct;
      c.sim_valid_pct = sim[i].valid_pct;
      if (std::isfinite(c.real_plane_std_m) && c.real_plane_std_m > 0 &&
          std::isfinite(c.sim_plane_std_m) && c.sim_plane_std_m > 0) {
        const double r = std::log(c.sim_plane_std_m / c.real_plane_std_m);
        sum_log += r * r;
        ++n_log;
        fit.mean_real_plane_std_m += c.real_plane_std_m;
        fit.mean_sim_plane_std_m += c.sim_plane_std_m;
      }
      if (std::isfinite(c.real_valid_pct) && std::isfinite(c.sim_valid_pct)) {
        const double r = c.sim_valid_pct - c.real_valid_pct;
        sum_valid += r * r;
        ++n_valid;
        fit.mean_real_valid_pct += c.real_valid_pct;
        fit.mean_sim_valid_pct += c.sim_valid_pct;
      }
      fit.cells.push_back(c);
    }
    if (n_log) {
      fit.rms_log_plane_std = std::sqrt(sum_log / n_log);
      fit.mean_real_plane_std_m /= n_log;
      fit.mean_sim_plane_std_m /= n_log;
    }
    if (n_valid) {
      fit.rms_valid_pct = std::sqrt(sum_valid / n_valid);
      fit.mean_real_valid_pct /= n_valid;
      fit.mean_sim_valid_pct /= n_valid;
    }
    result.sensor.scenarios.push_back(fit.fitted);
    result.scenarios.push_back(fit);
  }
  result.success = true;
  if (result.rows_skipped)
    result.message = std::to_string(result.rows_skipped) + " rows skipped (not ok or no target)";
  return result;
}

std::string FormatCalibration(const CalibrationResult& r) {
  std::string out;
  char line[256];
  std::snprintf(line, sizeof line, "%-9s %-6s %-4s %5s %5s %10s %10s %9s %9s\n", "light",
                "preset", "emit", "D_m", "A_deg", "real_std_m", "sim_std_m", "real_val%",
                "sim_val%");
  out += line;
  for (const auto& f : r.scenarios)
    for (const auto& c : f.cells) {
      std::snprintf(line, sizeof line, "%-9s %-6s %-4s %5.0f %5.0f %10.3f %10.3f %9.2f %9.2f\n",
                    f.fitted.light.c_str(), f.fitted.preset.c_str(), c.emitter.c_str(),
                    c.distance_m, c.angle_deg, c.real_plane_std_m, c.sim_plane_std_m,
                    c.real_valid_pct, c.sim_valid_pct);
      out += line;
    }
  std::snprintf(line, sizeof line, "\n%-9s %-6s %3s %10s %12s %9s %9s %9s %9s %8s %8s\n",
                "light", "preset", "n", "sigma_d_px", "invalid_prob", "real_std", "sim_std",
                "real_val", "sim_val", "rms_log", "rms_val");
  out += line;
  for (const auto& f : r.scenarios) {
    std::snprintf(line, sizeof line,
                  "%-9s %-6s %3d %10.4f %12.4f %9.3f %9.3f %9.2f %9.2f %8.3f %8.2f\n",
                  f.fitted.light.c_str(), f.fitted.preset.c_str(), f.recordings,
                  f.fitted.sigma_d_px, f.fitted.invalid_prob, f.mean_real_plane_std_m,
                  f.mean_sim_plane_std_m, f.mean_real_valid_pct, f.mean_sim_valid_pct,
                  f.rms_log_plane_std, f.rms_valid_pct);
    out += line + ("  " + f.report + "\n");
  }
  if (!r.message.empty()) out += "note: " + r.message + "\n";
  return out;
}

std::string CalibrationYaml(const CalibrationResult& r, const std::string& source) {
  std::ostringstream o;
  o << "calibration:\n"
    << "  source: \"" << source << "\"\n"
    << "  rows_used: " << r.rows_used << "\n"
    << "  rows_skipped: " << r.rows_skipped << "\n"
    << "  residuals: \"log(sim/real) plane_std_m and (sim - real) valid_pct / scale\"\n"
    << "  scenarios:\n";
  for (const auto& f : r.scenarios) {
    o << "    - {light: " << f.fitted.light << ", preset: " << f.fitted.preset
      << ", n: " << f.recordings << ", converged: " << (f.converged ? "true" : "false")
      << ", rms_log_plane_std: " << Num(f.rms_log_plane_std, 4)
      << ", rms_valid_pct: " << Num(f.rms_valid_pct, 4)
      << ", mean_real_plane_std_m: " << Num(f.mean_real_plane_std_m, 4)
      << ", mean_sim_plane_std_m: " << Num(f.mean_sim_plane_std_m, 4)
      << ", mean_real_valid_pct: " << Num(f.mean_real_valid_pct, 4)
      << ", mean_sim_valid_pct: " << Num(f.mean_sim_valid_pct, 4) << "}\n";
  }
  return o.str();
}

}  // namespace depthbias::gap
