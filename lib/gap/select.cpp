#include "gap/select.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include <Eigen/Dense>

#include "common/parallel.h"
#include "gap/report_util.h"
#include "gap/unexplained.h"

namespace depthbias::gap {
namespace {

double Logit(double p) {
  p = std::clamp(p, 1e-6, 1 - 1e-6);
  return std::log(p / (1 - p));
}
double Logistic(double x) { return 1.0 / (1.0 + std::exp(-x)); }

// z = (y − μ) / σ of the valid observations (NaN elsewhere).
}  // namespace

std::vector<double> Scaled(const GapModel& m, const std::vector<double>& mu) {
  std::vector<double> z(mu.size(), NAN);
  for (size_t o = 0; o < mu.size(); ++o)
    if (m.valid(o) && std::isfinite(mu[o])) z[o] = (m.y(o) - mu[o]) / m.noise(o);
  return z;
}

GapStat Stat(const GapModel& m, const std::vector<double>& z, const std::vector<char>& cells) {
  const int k_count = m.num_metrics();
  GapStat s;
  s.mean_sq.assign(k_count, 0.0);
  s.n.assign(k_count, 0);
  double total = 0;
  for (size_t o = 0; o < z.size(); ++o) {
    if (!cells[o / k_count] || !m.valid(o) || !std::isfinite(z[o])) continue;
    s.mean_sq[o % k_count] += z[o] * z[o];
    ++s.n[o % k_count];
    total += z[o] * z[o];
    ++s.count;
  }
  for (int k = 0; k < k_count; ++k) s.mean_sq[k] = s.n[k] ? s.mean_sq[k] / s.n[k] : NAN;
  s.overall = s.count ? total / s.count : NAN;
  return s;
}

double Shrink(const GapStat& before, const GapStat& after) {
  const double excess = before.overall - 1.0;
  return excess > 0 ? 100.0 * (before.overall - after.overall) / excess : NAN;
}

// Dispersion of each metric about a prediction: the φ ≥ 1 at which the mean deviance of its
// observations, 2ρ(z/√φ), equals its expectation under unit normal noise (a Pearson estimate
// made robust by the same Huber loss the fit uses).
std::vector<double> Dispersion(const GapModel& m, const std::vector<double>& mu,
                               const std::vector<char>& cells) {
  const int k_count = m.num_metrics();
  const double hk = m.settings().huber_k;
  auto dev = [hk](double r) {
    return hk <= 0 || std::fabs(r) <= hk ? r * r : 2 * hk * std::fabs(r) - hk * hk;
  };
  // E[2ρ(z)] for z ~ N(0, 1), by the midpoint rule over ±8.
  double expected = 0;
  for (int i = 0; i < 16000; ++i) {
    const double z = -8 + (i + 0.5) * 1e-3;
    expected += dev(z) * std::exp(-0.5 * z * z) / std::sqrt(2 * M_PI) * 1e-3;
  }
  // The log of the factor ≥ 0 at which `excess` (decreasing in it) reaches 0.
  auto solve = [](const auto& excess) {
    if (excess(0.0) <= 0) return 0.0;
    double lo = 0, hi = 1;
    while (excess(hi) > 0 && hi < 60) hi *= 2;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      (excess(mid) > 0 ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  };
  std::vector<double> phi(2 * static_cast<size_t>(k_count), 1.0);
  struct Obs { double r, sigma, tau; };
  for (int k = 0; k < k_count; ++k) {
    // Per independent unit (a test point, or a recording alone) its residuals, replicate noise
    // and placement scatter.
    std::map<long long, std::vector<Obs>> units;
    for (size_t o = k; o < mu.size(); o += k_count)
      if (cells[o / k_count] && m.valid(o) && std::isfinite(mu[o]))
        units[m.Unit(o)].push_back({m.y(o) - mu[o], m.replicate_noise(o), m.placement(o)});
    // Within a unit: each recording's departure from the unit's precision-weighted mean over its
    // own standard deviation σ·√(1 − w/W), which the placement the recordings share does not
    // enter (a recording alone: its residual over σ). Between: each unit's mean, of variance
    // ψ·τ² + φ/W. Where the recordings share the placement with loadings τ_i that differ (a
    // spread's floor per scenario, PlacementEstimate::tau_cell), the same split about the
    // shared displacement's estimate ξ = Σ(τ·r/σ²) / B, B = Σ τ²/σ²: departures r − τ·ξ over
    // σ·√(1 − τ²/(σ²·B)), and ξ of variance ψ + φ/B.
    std::vector<double> within;
    std::vector<Obs> means;  // r: the unit's mean, sigma: √(1/W), tau: its τ
    for (const auto& [unit, rs] : units) {
      if (unit < 0) {
        for (const Obs& x : rs) within.push_back(x.r / x.sigma);
        continue;
      }
      bool equal = true;
      for (const Obs& x : rs) equal = equal && x.tau == rs[0].tau;
      if (!equal) {
        double b = 0, a = 0;
        for (const Obs& x : rs) {
          b += x.tau * x.tau / (x.sigma * x.sigma);
          a += x.tau * x.r / (x.sigma * x.sigma);
        }
        const double xi = a / b;
        for (const Obs& x : rs) {
          const double lever = x.tau * x.tau / (x.sigma * x.sigma) / b;
          if (lever < 1 - 1e-9)
            within.push_back((x.r - x.tau * xi) / (x.sigma * std::sqrt(1 - lever)));
        }
        means.push_back({xi, std::sqrt(1 / b), 1.0});
        continue;
      }
      double sw = 0, swr = 0;
      for (const Obs& x : rs) sw += 1 / (x.sigma * x.sigma), swr += x.r / (x.sigma * x.sigma);
      const double mean = swr / sw;
      for (const Obs& x : rs) {
        const double share = 1 / (x.sigma * x.sigma) / sw;
        if (share < 1 - 1e-9) within.push_back((x.r - mean) / (x.sigma * std::sqrt(1 - share)));
      }
      if (rs[0].tau > 0) means.push_back({mean, std::sqrt(1 / sw), rs[0].tau});
    }
    phi[k] = std::exp(solve([&](double lp) {
      if (within.empty()) return -1.0;
      const double sc = std::exp(-0.5 * lp);
      double sum = 0;
      for (double v : within) sum += dev(v * sc);
      return sum / static_cast<double>(within.size()) - expected;
    }));
    phi[k_count + k] = std::exp(solve([&](double lp) {
      if (means.empty()) return -1.0;
      const double psi = std::exp(lp);
      double sum = 0;
      for (const Obs& x : means)
        sum += dev(x.r / std::sqrt(psi * x.tau * x.tau + phi[k] * x.sigma * x.sigma));
      return sum / static_cast<double>(means.size()) - expected;
    }));
  }
  return phi;
}

namespace {

// The node index nearest a value on an axis.
int NearestNode(const Axis& a, double value) {
  int best = 0;
  for (size_t i = 1; i < a.nodes.size(); ++i)
    if (std::fabs(a.nodes[i] - value) < std::fabs(a.nodes[best] - value))
      best = static_cast<int>(i);
  return best;
}

// Signature of a candidate: its change of every valid observation at its reference size (shared
// over the cells), in weighted noise units, with the calibration's directions of each scenario
// projected out. r2_sigma, r2_p, r2_both: the share of its squared norm those directions take.
std::vector<double> Signature(const GapModel& m, int candidate, double* r2_sigma, double* r2_p,
                              double* r2_both) {
  const Design& d = m.design();
  const Simulations& s = m.sims();
  const Candidate& cand = m.surface(candidate).candidate;
  Term term{candidate, Scope::kShared, {std::vector<int>(cand.axes.size(), -1)}};
  double u[2] = {0, 0};
  for (size_t a = 0; a < cand.axes.size(); ++a) {
    if (cand.axes[a].discrete)
      term.discrete_node[0][a] = NearestNode(cand.axes[a], cand.axes[a].reference);
    u[a] = m.ToCoord(candidate, static_cast<int>(a), cand.axes[a].reference);
  }
  const int k_count = m.num_metrics();
  std::vector<double> sig(m.num_obs(), 0.0);
  double norm = 0, along_sigma = 0, along_p = 0, along_both = 0;
  for (int sc = 0; sc < d.num_scenarios(); ++sc) {
    std::vector<size_t> obs;
    for (int c = 0; c < d.num_cells(); ++c)
      if (d.scenario[c] == sc)
        for (int k = 0; k < k_count; ++k)
          if (m.valid(static_cast<size_t>(c) * k_count + k))
            obs.push_back(static_cast<size_t>(c) * k_count + k);
    if (obs.empty()) continue;
    Eigen::VectorXd v(obs.size());
    Eigen::MatrixXd a(obs.size(), 2);
    for (size_t i = 0; i < obs.size(); ++i) {
      const double w = m.weight(obs[i]);
      v(i) = m.Delta(term, u, obs[i]) * w;
      a(i, 0) = s.jac_log_sigma[obs[i]] * w;
      a(i, 1) = s.jac_logit_p[obs[i]] * w;
    }
    auto projected = [&](const Eigen::MatrixXd& cols) {
      const Eigen::MatrixXd g = cols.transpose() * cols +
                                1e-12 * Eigen::MatrixXd::Identity(cols.cols(), cols.cols());
      return Eigen::VectorXd(cols * g.ldlt().solve(cols.transpose() * v));
    };
    const Eigen::VectorXd both = projected(a);
    norm += v.squaredNorm();
    along_sigma += projected(a.col(0)).squaredNorm();
    along_p += projected(a.col(1)).squaredNorm();
    along_both += both.squaredNorm();
    const Eigen::VectorXd rest = v - both;
    for (size_t i = 0; i < obs.size(); ++i) sig[obs[i]] = rest(i);
  }
  *r2_sigma = norm > 0 ? along_sigma / norm : 0;
  *r2_p = norm > 0 ? along_p / norm : 0;
  *r2_both = norm > 0 ? along_both / norm : 0;
  return sig;
}

double Correlation(const std::vector<double>& a, const std::vector<double>& b) {
  double ab = 0, aa = 0, bb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    ab += a[i] * b[i];
    aa += a[i] * a[i];
    bb += b[i] * b[i];
  }
  return aa > 0 && bb > 0 ? ab / std::sqrt(aa * bb) : 0.0;
}

}  // namespace

bool BeatsByOneSe(const GapModel& m, const HeldOut& wider, const HeldOut& simpler) {
  std::map<long long, double> a, b;
  m.DataDeviance(wider.mu, wider.cells, &a);
  m.DataDeviance(simpler.mu, simpler.cells, &b);
  for (const auto& kv : a) b.emplace(kv.first, 0.0);
  std::vector<double> diff;  // wider − simpler, per unit
  for (const auto& [unit, v] : b) {
    const auto it = a.find(unit);
    diff.push_back((it == a.end() ? 0.0 : it->second) - v);
  }
  const double n = static_cast<double>(diff.size());
  if (n < 2) return false;
  double mean = 0, ss = 0;
  for (double d : diff) mean += d / n;
  for (double d : diff) ss += (d - mean) * (d - mean);
  const double se_sum = std::sqrt(n * ss / (n - 1));  // of Σ diff
  return n * mean < -se_sum;
}

Selection Select(GapModel& model, const PlacementEstimate& placement,
                 const std::vector<char>& train, const std::vector<int>& fold, int num_folds,
                 const DiagnoseParams& params) {
  Selection r;
  const Design& design = model.design();
  const Simulations& sims = model.sims();
  const int n_cand = static_cast<int>(sims.surfaces.size());
  const std::vector<double> z_base = Scaled(model, sims.base);
  const GapStat baseline = Stat(model, z_base, train);

  // The calibrated base: the reference every effect is judged against.
  model.SetDispersion(std::vector<double>(model.num_metrics(), 1.0));
  for (int i = 0; i < n_cand; ++i) model.SetAbsorbs(i, 0);
  ModelFit m0 = FitTerms(model, {}, train);
  if (!m0.success) {
    r.message = "calibration: " + m0.message;
    return r;
  }
  model.SetDispersion(Dispersion(model, model.Predict(m0), train));
  m0 = FitTerms(model, {}, train, &m0);
  HeldOut m0_ho = CrossValidate(model, {}, fold, num_folds, m0, train);
  if (!m0.success || !m0_ho.success) {
    r.message = "calibration: " + (m0.success ? m0_ho.message : m0.message);
    return r;
  }
  r.dispersion = model.dispersion();
  const double log_n = std::log(static_cast<double>(m0.num_obs));

  // Signatures, and the calibration components each candidate duplicates.
  std::vector<double> r2_both(n_cand);
  r.r2_sigma.assign(n_cand, 0);
  r.r2_p.assign(n_cand, 0);
  std::vector<std::vector<double>> signature(n_cand);
  const double r2_limit = params.absorb_r * params.absorb_r;
  for (int i = 0; i < n_cand; ++i) {
    signature[i] = Signature(model, i, &r.r2_sigma[i], &r.r2_p[i], &r2_both[i]);
    model.SetAbsorbs(i, (r.r2_sigma[i] >= r2_limit ? 1 : 0) | (r.r2_p[i] >= r2_limit ? 2 : 0));
  }

  // Every candidate alone, shared, per light and per scenario. The fits read the model alone and
  // run side by side (params.simulate.threads); their results are taken in the candidates' order.
  const GapModel& fixed = model;
  const int threads = params.simulate.threads;
  auto dbic = [&](const ModelFit& f) {
    return f.success ? m0.Deviance() - f.Deviance() - (f.num_params - m0.num_params) * log_n
                     : -INFINITY;
  };
  constexpr Scope kGrouped[] = {Scope::kPerLight, Scope::kPerScenario};
  struct Alone {
    ModelFit shared;
    ModelFit grouped[2];  // per light, per scenario (kGrouped's order); unfitted where they
                          // do not apply
    Scope scope = Scope::kShared;
    HeldOut ho;
    std::vector<double> mu;
    const ModelFit& Kept() const {
      return scope == Scope::kShared ? shared : grouped[scope == Scope::kPerLight ? 0 : 1];
    }
  };
  std::vector<Alone> alone(n_cand);
  // shared_only: the shared fits alone, the widest model's start.
  auto fit_alone = [&](bool shared_only) {
    common::ForEachIndex(static_cast<size_t>(n_cand), threads, [&](size_t k) {
      const int i = static_cast<int>(k);
      Alone& a = alone[k];
      a = Alone{};
      a.shared = FitCandidate(fixed, i, Scope::kShared, train);
      if (shared_only) return;
      for (int g = 0; g < 2; ++g)
        if (ScopeApplies(design, kGrouped[g]))
          a.grouped[g] = FitCandidate(fixed, i, kGrouped[g], train, &a.shared);
      // A grouped scope only when it earns both ways: the best by BIC (the fewer groups win a
      // tie), and on the held-out cells against the shared fit by more than one standard error
      // (several groups' values can buy BIC from the simulation's own misfit of a large effect,
      // or from the placement draws of each group's test points, and fit it differently in each).
      double best_bic = a.shared.success ? dbic(a.shared) : -INFINITY;
      for (int g = 0; g < 2; ++g)
        if (a.grouped[g].success && dbic(a.grouped[g]) > best_bic) {
          best_bic = dbic(a.grouped[g]);
          a.scope = kGrouped[g];
        }
      if (!a.shared.success && a.scope == Scope::kShared) return;
      a.ho = CrossValidate(fixed, {a.Kept().terms[0].term}, fold, num_folds, a.Kept(), train);
      if (a.scope != Scope::kShared && a.shared.success) {
        HeldOut ho = CrossValidate(fixed, {a.shared.terms[0].term}, fold, num_folds, a.shared,
                                   train);
        if (ho.success && (!a.ho.success || !BeatsByOneSe(fixed, a.ho, ho))) {
          a.scope = Scope::kShared;
          a.ho = std::move(ho);
        }
      }
      if (a.ho.success) a.mu = fixed.Predict(a.Kept());
    });
  };
  fit_alone(true);

  // Dispersion about the widest model: every candidate the calibration does not absorb and
  // whose axes are all continuous (a discrete width cannot be turned off), shared, fitted
  // together from each one's fit alone, in units of the noise (φ = 1), then once more at the
  // dispersion found. About the calibrated base, an effect the simulator lacks would count as
  // noise: it widens its own metric's φ (a 6 % depth scale: the median's φ 7), until the metric
  // where it lives no longer tells candidates apart and other metrics decide. The candidates
  // alone are refitted at that φ, and every fit of the selection keeps it.
  {
    std::vector<Term> wide;
    ModelFit start = m0;
    for (int i = 0; i < n_cand; ++i) {
      const Candidate& cand = sims.surfaces[i].candidate;
      const bool discrete = std::any_of(cand.axes.begin(), cand.axes.end(),
                                        [](const Axis& a) { return a.discrete; });
      if (model.Absorbs(i) || discrete) continue;
      wide.push_back(Term{i, Scope::kShared, {std::vector<int>(cand.axes.size(), -1)}});
      if (alone[i].shared.success) start.terms.push_back(alone[i].shared.terms[0]);
    }
    const std::vector<double> phi_base = model.dispersion();
    model.SetDispersion(std::vector<double>(model.num_metrics(), 1.0));
    ModelFit wide_fit;
    for (int round = 0; round < 2 && !wide.empty(); ++round) {
      wide_fit = FitTerms(model, wide, train, round > 0 ? &wide_fit : &start);
      if (!wide_fit.success) break;
      model.SetDispersion(Dispersion(model, model.Predict(wide_fit), train));
    }
    if (!wide_fit.success) {
      model.SetDispersion(phi_base);
      fit_alone(false);
    } else {
      m0 = FitTerms(model, {}, train, &m0);
      m0_ho = CrossValidate(model, {}, fold, num_folds, m0, train);
      if (!m0.success || !m0_ho.success) {
        r.message = "calibration: " + (m0.success ? m0_ho.message : m0.message);
        return r;
      }
      r.dispersion = model.dispersion();
      fit_alone(false);
    }
  }
  for (int i = 0; i < n_cand; ++i) {
    EffectResult e;
    e.name = sims.surfaces[i].candidate.effect;
    const Alone& a = alone[i];
    e.delta_bic_shared = dbic(a.shared);
    e.delta_bic_per_light = dbic(a.grouped[0]);
    e.delta_bic_per_scenario = dbic(a.grouped[1]);
    if (!a.Kept().success) {
      r.message = e.name + ": " + a.shared.message;
      return r;
    }
    e.scope = a.scope;
    e.fit = a.Kept().terms[0];
    e.delta_bic = dbic(a.Kept());
    const HeldOut& ho = alone[i].ho;
    if (!ho.success) {
      r.message = e.name + ": " + ho.message;
      return r;
    }
    e.heldout_gain = m0_ho.data_deviance - ho.data_deviance;
    e.in_sample = Stat(model, Scaled(model, alone[i].mu), train);
    e.heldout = Stat(model, Scaled(model, ho.mu), ho.cells);
    e.shrink_in_sample_pct = Shrink(baseline, e.in_sample);
    e.shrink_heldout_pct = Shrink(Stat(model, z_base, ho.cells), e.heldout);
    e.earns = e.delta_bic > 0 && e.heldout_gain > 0;
    e.signature = signature[i];
    r.effects.push_back(std::move(e));
  }

  // Confounded pairs: between effects, and of an effect with the calibration.
  for (int i = 0; i < n_cand; ++i) {
    if (model.Absorbs(i) & 1)
      r.confounded.push_back({r.effects[i].name, "calibration:sigma_d", std::sqrt(r.r2_sigma[i])});
    if (model.Absorbs(i) & 2)
      r.confounded.push_back({r.effects[i].name, "calibration:hole_prob", std::sqrt(r.r2_p[i])});
    for (int j = i + 1; j < n_cand; ++j) {
      const double c = Correlation(r.effects[i].signature, r.effects[j].signature);
      r.correlations.push_back({r.effects[i].name, r.effects[j].name, c});
      if (std::fabs(c) >= params.confounded_r)
        r.confounded.push_back({r.effects[i].name, r.effects[j].name, c});
    }
  }
  auto confounded = [&](int i, int j) {
    for (const auto& c : r.confounded)
      if ((c.a == r.effects[i].name && c.b == r.effects[j].name) ||
          (c.b == r.effects[i].name && c.a == r.effects[j].name))
        return true;
    return false;
  };

  // Forward selection from the calibrated base. An effect along a calibration direction is
  // never selected: the table cannot tell it from the recalibration.
  std::vector<int> order(n_cand);
  for (int i = 0; i < n_cand; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return r.effects[a].heldout_gain > r.effects[b].heldout_gain;
  });
  std::vector<Term> terms;
  ModelFit current = m0;
  HeldOut current_ho = m0_ho;
  for (int step = 0; step < params.max_selected; ++step) {
    int best = -1;
    double best_dbic = 0, best_gain = 0;  // the largest held-out gain among those earning both
    ModelFit best_fit;
    HeldOut best_ho;
    std::vector<int> open;  // the candidates tried at this step, in order
    for (int i : order) {
      if (model.Absorbs(i)) continue;
      if (std::find(r.chosen.begin(), r.chosen.end(), i) != r.chosen.end()) continue;
      bool clash = false;
      for (int j : r.chosen) clash = clash || confounded(i, j);
      if (clash) continue;
      open.push_back(i);
    }
    // The trials side by side, judged in order.
    struct Trial {
      ModelFit fit;
      double dbic = 0;
      HeldOut ho;
    };
    std::vector<Trial> trials(open.size());
    common::ForEachIndex(open.size(), threads, [&](size_t k) {
      const int i = open[k];
      Trial& t = trials[k];
      std::vector<Term> trial = terms;
      trial.push_back(r.effects[i].fit.term);
      ModelFit start = current;
      start.terms.push_back(r.effects[i].fit);
      t.fit = FitTerms(fixed, trial, train, &start);
      if (!t.fit.success) return;
      t.dbic = current.Deviance() - t.fit.Deviance() -
               (t.fit.num_params - current.num_params) * log_n;
      if (t.dbic <= 0) return;
      t.ho = CrossValidate(fixed, trial, fold, num_folds, t.fit, train);
    });
    for (size_t k = 0; k < open.size(); ++k) {
      Trial& t = trials[k];
      if (!t.fit.success || t.dbic <= 0 || !t.ho.success) continue;
      const double gain = current_ho.data_deviance - t.ho.data_deviance;
      if (gain <= best_gain) continue;
      best = open[k], best_dbic = t.dbic, best_gain = gain, best_fit = t.fit,
      best_ho = std::move(t.ho);
    }
    if (best < 0) break;
    r.chosen.push_back(best);
    terms.push_back(r.effects[best].fit.term);
    current = best_fit;
    current_ho = std::move(best_ho);
    r.steps.push_back({r.effects[best].name, r.effects[best].scope, best_dbic, best_gain});
  }

  auto keep_only = [&](const std::vector<char>& keep) {
    if (!KeepSteps(model, m0, keep, train, fold, num_folds, &r.steps, &current, &current_ho,
                   &r.chosen))
      r.message = "the refit without the dropped effects failed";
  };
  using text::Num;

  // The open world before a registered cause: where the calibrated base's median bias departs
  // from some distance on as a step (its shared departure is beyond chance and a step explains
  // it better than every smooth law in distance, constant, ∝ D and ∝ D², by more than a
  // parameter's price: MedianStepFrom, read whatever group the rest's search names), no range
  // law explains it, and one kept there would take an effect the registry does not have for the
  // nearest one it has (a far over-read of 0.5 m from 12 m on was kept as a −0.18 px offset,
  // one from 8 m on as a depth scale of 0.04). The step is reported in `unexplained` instead.
  if (!r.steps.empty()) {
    RestParams rp;
    rp.alpha = params.alpha;
    const double from = MedianStepFrom(model, model.Predict(m0), placement, train, rp);
    if (std::isfinite(from)) {
      const std::string step = "step from " + Num(from) + " m (distance ≥ " + Num(from) + " m)";
      std::vector<char> keep(r.steps.size(), 1);
      for (size_t i = 0; i < r.steps.size(); ++i) {
        if (!sims.surfaces[r.chosen[i]].candidate.range_law) continue;
        keep[i] = 0;
        r.dropped.push_back(r.steps[i].effect +
                            " (a range law; the calibrated base's median bias departs as a " +
                            step + ", which no range law gives)");
      }
      keep_only(keep);
    }
  }
  // A range law the spreads contradict is not kept (MedianWithoutSpreads).
  if (!MedianWithoutSpreads(model, m0, train, fold, num_folds, &current, &current_ho, &r))
    r.message = "the refit without the dropped effects failed";
  // An effect along the calibration is never selected (it is named "one of" with it), and a
  // kept effect it can stand in for is named "one of" with it too (AlongCalibration).
  if (!r.steps.empty()) keep_only(AlongCalibration(model, m0, current, train, &r));
  r.m0 = std::move(m0);
  r.m0_ho = std::move(m0_ho);
  r.current = std::move(current);
  r.current_ho = std::move(current_ho);
  r.success = true;
  return r;
}

bool KeepSteps(const GapModel& model, const ModelFit& m0, const std::vector<char>& keep,
               const std::vector<char>& train, const std::vector<int>& fold, int num_folds,
               std::vector<SelectionStep>* steps, ModelFit* current, HeldOut* current_ho,
               std::vector<int>* chosen) {
  std::vector<Term> kept;
  ModelFit start = m0;
  std::vector<SelectionStep> kept_steps;
  std::vector<int> kept_chosen;
  for (size_t i = 0; i < steps->size(); ++i) {
    if (!keep[i]) continue;
    kept.push_back(current->terms[i].term);
    start.terms.push_back(current->terms[i]);
    kept_steps.push_back((*steps)[i]);
    if (chosen) kept_chosen.push_back((*chosen)[i]);
  }
  if (kept_steps.size() == steps->size()) return true;
  *steps = std::move(kept_steps);
  if (chosen) *chosen = std::move(kept_chosen);
  ModelFit refit = FitTerms(model, kept, train, &start);
  HeldOut refit_ho = CrossValidate(model, kept, fold, num_folds, refit, train);
  if (!refit.success || !refit_ho.success) {
    current->terms = start.terms;
    return false;
  }
  *current = std::move(refit);
  *current_ho = std::move(refit_ho);
  return true;
}

std::string SizeText(const Candidate& c, const TermFit& t) {
  std::string s;
  for (size_t a = 0; a < c.axes.size(); ++a) {
    s += (s.empty() ? "" : ", ") + c.axes[a].param + " ";
    for (size_t g = 0; g < t.values.size(); ++g)
      s += (g ? " / " : "") + text::Num(t.values[g][a]);
  }
  return s;
}

std::vector<sim::SimParams> SelectedParams(const Simulations& sims, const sim::SimParams& base,
                                           const ModelFit& fit, const Design& design) {
  const int num_scenarios = design.num_scenarios();
  std::vector<sim::SimParams> per(num_scenarios, base);
  std::string why;
  for (int s = 0; s < num_scenarios; ++s) {
    per[s].sensor = sims.sensor;
    auto& sc = per[s].sensor.scenarios[s];
    if (static_cast<int>(fit.nuisance.size()) == num_scenarios) {
      sc.sigma_d_px *= std::exp(fit.nuisance[s][0]);
      sc.invalid_prob = Logistic(Logit(sc.invalid_prob) + fit.nuisance[s][1]);
    }
    std::vector<sim::EffectSpec> specs;
    for (const TermFit& t : fit.terms)
      specs.push_back(SpecAt(sims.surfaces[t.term.candidate].candidate,
                             t.values[ScopeGroupOf(design, t.term.scope, s)]));
    if (!sim::BuildDepartures(specs, &per[s].departures, &why))
      throw std::invalid_argument("the selected effects: " + why);
  }
  return per;
}

}  // namespace depthbias::gap
