#include "gap/nested.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <thread>

#include "gap/localize.h"
#include "gap/select.h"
#include "gap/unexplained.h"

namespace depthbias::gap {

namespace {

// The held-out cells (`held`) simulated with `fit` added to the base, as [obs] values (NaN
// elsewhere).
std::vector<double> SimulateHeld(const Design& d, const Simulations& sims,
                                 const sim::SimParams& base, const DiagnoseParams& params,
                                 const std::vector<char>& held, const ModelFit& fit) {
  const int kk = d.num_metrics();
  SimulateOptions options = params.simulate;
  options.threads = 1;  // the folds run side by side
  const std::vector<double> v =
      SimulateSelection(SelectedParams(sims, base, fit, d), Subset(d, held), base, options);
  std::vector<double> mu(d.real.size(), NAN);
  int i = 0;
  for (int c = 0; c < d.num_cells(); ++c) {
    if (!held[c]) continue;
    for (int k = 0; k < kk; ++k)
      mu[static_cast<size_t>(c) * kk + k] = v[static_cast<size_t>(i) * kk + k];
    ++i;
  }
  return mu;
}

// Σz² over the finite entries.
double SumSq(const std::vector<double>& z) {
  double s = 0;
  for (double v : z)
    if (std::isfinite(v)) s += v * v;
  return s;
}

// One outer fold diagnosed without its cells.
struct FoldRun {
  NestedFold fold;
  std::vector<char> held;
  std::vector<double> zb, z0, z1, zs, zsc;
  bool ok = true;
  std::string message;
};

FoldRun RunFold(const Design& d, const Simulations& sims, const sim::SimParams& base,
                const DiagnoseParams& params, const std::vector<int>& fold, int num_folds,
                int f) {
  FoldRun out;
  const int kk = d.num_metrics();
  const size_t obs = d.real.size();
  std::vector<char> train(d.num_cells(), 0);
  out.held.assign(d.num_cells(), 0);
  NestedFold& nf = out.fold;
  nf.index = f;
  for (int c = 0; c < d.num_cells(); ++c) {
    train[c] = fold[c] != f;
    out.held[c] = fold[c] == f;
    if (out.held[c] && nf.held.empty()) nf.held = LevelName(d.cells[c], 0);
    nf.cells += out.held[c];
  }
  if (nf.cells == 0) return out;
  try {
    const NoiseEstimate noise = EstimateNoise(d, sims, train);
    const PlacementEstimate placement =
        params.placement ? EstimatePlacement(d, sims, noise, train, params.placement_alpha)
                         : PlacementEstimate();
    GapModel model(d, sims, noise, params.fit, &placement);
    DiagnoseParams one_thread = params;  // the folds run side by side
    one_thread.simulate.threads = 1;
    const Selection sel = Select(model, placement, train, fold, num_folds, one_thread);
    if (!sel.success) throw std::invalid_argument(sel.message);
    for (const auto& s : sel.steps) nf.selected.push_back(s.effect);
    nf.fit = sel.current;
    for (const ModelFit* fit : {&sel.m0, &sel.current}) {  // their σ_d and hole probability
      ModelFit nuisance = *fit;
      nuisance.terms.clear();  // the effects' departures are not needed (nor built)
      auto& to = fit == &sel.m0 ? nf.scenarios_calibrated : nf.scenarios_selected;
      const auto per = SelectedParams(sims, sim::SimParams(), nuisance, d);
      for (int s = 0; s < d.num_scenarios(); ++s) to.push_back(per[s].sensor.scenarios[s]);
    }
    nf.y.assign(obs, NAN);
    nf.unit.assign(obs, NAN);
    for (size_t o = 0; o < obs; ++o)
      if (out.held[o / kk] && model.valid(o)) nf.y[o] = model.y(o), nf.unit[o] = model.noise(o);
    const std::vector<double> mu0 = model.Predict(sel.m0), mu1 = model.Predict(sel.current);
    nf.deviance_calibrated = model.DataDeviance(mu0, out.held);
    nf.deviance_selected = model.DataDeviance(mu1, out.held);
    out.zb = Scaled(model, sims.base);
    out.z0 = Scaled(model, mu0);
    out.z1 = Scaled(model, mu1);
    out.zs.assign(obs, NAN);
    out.zsc.assign(obs, NAN);
    try {
      // The held-out cells simulated with the fold's calibrated base, and with its selection.
      auto simulate = [&](const ModelFit& fit) {
        return SimulateHeld(d, sims, base, params, out.held, fit);
      };
      const std::vector<double> mu = simulate(sel.current);
      out.zsc = sel.steps.empty() ? Scaled(model, mu) : Scaled(model, simulate(sel.m0));
      out.zs = Scaled(model, mu);
      const double all_sq = SumSq(out.zs), calibrated_sq = SumSq(out.zsc);
      nf.simulated_calibrated_sq = calibrated_sq;
      nf.simulated_sq = all_sq;
      nf.simulated_calibrated_sq_metric.assign(kk, 0.0);
      nf.simulated_sq_metric.assign(kk, 0.0);
      for (size_t o = 0; o < obs; ++o) {
        const double a = out.zsc[o], b = out.zs[o];
        if (std::isfinite(a)) nf.simulated_calibrated_sq_metric[o % kk] += a * a;
        if (std::isfinite(b)) nf.simulated_sq_metric[o % kk] += b * b;
      }
      // Each effect's own part: the selection simulated without it, the others at their values.
      for (size_t j = 0; j < sel.current.terms.size(); ++j) {
        std::vector<double> without = out.zsc;
        if (sel.current.terms.size() > 1) {
          ModelFit rest = sel.current;
          rest.terms.erase(rest.terms.begin() + static_cast<long>(j));
          without = Scaled(model, simulate(rest));
        }
        nf.effect_gain_simulated.push_back(SumSq(without) - all_sq);
        nf.effect_share_moved.push_back(MovedShare(without, out.zs, out.zsc, kk));
      }
      nf.simulated = true;
    } catch (const std::exception& e) {
      out.message = "fold " + nf.held + ": not simulated: " + e.what();
    }
  } catch (const std::exception& e) {
    out.ok = false;
    out.message = "fold " + nf.held + ": " + e.what();
  }
  return out;
}

}  // namespace

double MovedShare(const std::vector<double>& without, const std::vector<double>& with,
                  const std::vector<double>& calibrated, int metrics) {
  std::vector<double> move(metrics, 0.0), gain(metrics, 0.0), gap(metrics, 0.0);
  for (size_t o = 0; o < without.size() && o < with.size() && o < calibrated.size(); ++o) {
    const double a = without[o], b = with[o], c = calibrated[o];
    if (!std::isfinite(a) || !std::isfinite(b) || !std::isfinite(c)) continue;
    const size_t k = o % static_cast<size_t>(metrics);
    move[k] += (a - b) * (a - b);
    gain[k] += a * a - b * b;
    gap[k] += c * c;
  }
  double num = 0, den = 0;
  for (int k = 0; k < metrics; ++k) {
    num += move[k] * gain[k];
    den += move[k] * gap[k];
  }
  return den > 0 ? num / den : NAN;
}

Nested RunNested(const Design& d, const Simulations& sims, const sim::SimParams& base,
                 const DiagnoseParams& params, const std::vector<int>& fold, int num_folds,
                 const GapModel& full) {
  Nested n;
  const int kk = d.num_metrics();
  const size_t obs = d.real.size();
  n.cells.assign(d.num_cells(), 0);
  for (auto* z : {&n.z_baseline, &n.z_calibrated, &n.z_selected, &n.z_simulated,
                  &n.z_simulated_calibrated, &n.unit})
    z->assign(obs, NAN);
  // The folds side by side, as many at once as the simulation may use threads.
  std::vector<FoldRun> runs(num_folds);
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int f = next++; f < num_folds; f = next++)
      runs[f] = RunFold(d, sims, base, params, fold, num_folds, f);
  };
  const int workers = std::max(1, std::min(params.simulate.threads, num_folds));
  std::vector<std::thread> pool;
  for (int i = 1; i < workers; ++i) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  bool all_simulated = true;
  for (FoldRun& run : runs) {
    if (run.fold.cells == 0) continue;
    if (!run.ok) {
      n.message = run.message;
      return n;
    }
    if (!run.fold.simulated) {
      all_simulated = false;
      n.message = run.message;
    }
    n.gain += run.fold.deviance_calibrated - run.fold.deviance_selected;
    for (int c = 0; c < d.num_cells(); ++c) {
      if (!run.held[c]) continue;
      n.cells[c] = 1;
      for (int k = 0; k < kk; ++k) {
        const size_t o = static_cast<size_t>(c) * kk + k;
        n.z_baseline[o] = run.zb[o];
        n.z_calibrated[o] = run.z0[o];
        n.z_selected[o] = run.z1[o];
        n.z_simulated[o] = run.zs[o];
        n.z_simulated_calibrated[o] = run.zsc[o];
        n.unit[o] = run.fold.unit[o];
      }
    }
    n.folds.push_back(std::move(run.fold));
  }
  n.baseline = Stat(full, n.z_baseline, n.cells);
  n.calibrated = Stat(full, n.z_calibrated, n.cells);
  n.selected = Stat(full, n.z_selected, n.cells);
  n.shrink_heldout_nested_pct = Shrink(n.baseline, n.selected);
  if (all_simulated) {
    n.simulated = Stat(full, n.z_simulated, n.cells);
    n.shrink_simulated_pct = Shrink(n.baseline, n.simulated);
    n.simulated_calibrated = Stat(full, n.z_simulated_calibrated, n.cells);
    n.gain_simulated = 0;
    for (size_t o = 0; o < obs; ++o) {
      const double a = n.z_simulated_calibrated[o], b = n.z_simulated[o];
      if (std::isfinite(a) && std::isfinite(b)) n.gain_simulated += a * a - b * b;
    }
    n.share_moved = MovedShare(n.z_simulated_calibrated, n.z_simulated,
                               n.z_simulated_calibrated, kk);
  }
  n.run = true;
  return n;
}

bool RestrictNested(const Design& d, const Simulations& sims, const sim::SimParams& base,
                    const DiagnoseParams& params, const std::vector<int>& fold,
                    const GapModel& full, const std::vector<std::string>& keep, Nested* n) {
  n->kept.clear();
  n->simulated_kept = GapStat();
  n->gain_simulated_kept = n->share_moved_kept = NAN;
  if (!n->run || std::isnan(n->gain_simulated)) return false;
  auto kept = [&](const std::string& e) {
    return std::find(keep.begin(), keep.end(), e) != keep.end();
  };
  bool needed = false;
  for (const NestedFold& f : n->folds)
    for (const std::string& e : f.selected) needed |= !kept(e);
  if (!needed) return false;
  const int kk = d.num_metrics();
  std::vector<double> z = n->z_simulated;
  // The folds side by side, as many at once as the simulation may use threads.
  std::vector<std::string> failed(n->folds.size());
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t i = next++; i < n->folds.size(); i = next++) {
      const NestedFold& f = n->folds[i];
      ModelFit part = f.fit;
      part.terms.clear();
      for (size_t j = 0; j < f.selected.size() && j < f.fit.terms.size(); ++j)
        if (kept(f.selected[j])) part.terms.push_back(f.fit.terms[j]);
      if (part.terms.size() == f.fit.terms.size()) continue;  // its selection is kept whole
      std::vector<char> held(d.num_cells(), 0);
      for (int c = 0; c < d.num_cells(); ++c) held[c] = fold[c] == f.index;
      if (part.terms.empty()) {  // the fold's calibrated base, simulated already
        for (size_t o = 0; o < z.size(); ++o)
          if (held[o / kk]) z[o] = n->z_simulated_calibrated[o];
        continue;
      }
      try {
        const std::vector<double> mu = SimulateHeld(d, sims, base, params, held, part);
        for (size_t o = 0; o < z.size(); ++o)
          if (held[o / kk])
            z[o] = std::isfinite(f.unit[o]) && std::isfinite(mu[o]) ? (f.y[o] - mu[o]) / f.unit[o]
                                                                     : NAN;
      } catch (const std::exception& e) {
        failed[i] = e.what();
      }
    }
  };
  const int workers =
      std::max(1, std::min(params.simulate.threads, static_cast<int>(n->folds.size())));
  std::vector<std::thread> pool;
  for (int i = 1; i < workers; ++i) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  for (const std::string& why : failed)
    if (!why.empty()) return false;
  n->kept = keep;
  n->simulated_kept = Stat(full, z, n->cells);
  n->gain_simulated_kept = 0;
  for (size_t o = 0; o < z.size(); ++o) {
    const double a = n->z_simulated_calibrated[o], b = z[o];
    if (std::isfinite(a) && std::isfinite(b)) n->gain_simulated_kept += a * a - b * b;
  }
  n->share_moved_kept = MovedShare(n->z_simulated_calibrated, z, n->z_simulated_calibrated, kk);
  return true;
}

bool OwnPart(const NestedFold& f, size_t j, double part[2]) {
  if (!f.simulated || !(f.simulated_calibrated_sq > 0) || j >= f.effect_gain_simulated.size() ||
      j >= f.effect_share_moved.size())
    return false;
  part[0] = f.effect_gain_simulated[j] / f.simulated_calibrated_sq;
  part[1] = f.effect_share_moved[j];
  return true;
}

}  // namespace depthbias::gap
