// The diagnosis proved where the answer is known (DESIGN.md, "The sim-to-real gap"): the
// article's protocol simulated with an effect the base model lacks, then diagnosed with the base
// model. One process runs every case: the simulations of the candidates' grids are made once
// and shared (ctest runs this binary whole).
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "gap/cases.h"
#include "io/atomic_file.h"
#include "io/metrics_csv.h"
#include "sim/config_yaml.h"

namespace depthbias::gap {
namespace {

constexpr std::uint64_t kTruthSeed = 1000;

sim::SimParams Base() {
  sim::SimParams p;
  std::string why, sensor;
  const std::string dir = DEPTHBIAS_SOURCE_DIR "/config/";
  if (!sim::ParseProtocolYaml(io::ReadFile(dir + "protocol_paper.yaml"), &p.protocol, &sensor,
                              &why) ||
      !sim::ParseSensorYaml(io::ReadFile(dir + sensor), &p.sensor, &why))
    throw std::runtime_error("fixture: " + why);
  return p;
}

DiagnoseParams Params() {
  DiagnoseParams d;
  d.verify = false;
  d.simulate.threads = 2;
  return d;
}

// The protocol's table with the given effects, at a seed of its own.
Design TableWith(const std::vector<sim::EffectSpec>& effects, std::uint64_t seed) {
  sim::SimParams truth = Base();
  truth.seed = seed;
  std::string why;
  if (!sim::BuildDepartures(effects, &truth.departures, &why))
    throw std::runtime_error("fixture: " + why);
  Design d;
  if (!BuildDesign(SimulateTable(truth, Params().simulate), &d, &why))
    throw std::runtime_error("fixture: " + why);
  return d;
}

// The candidates' simulations on the protocol's cells, made once for the whole binary.
const Simulations& SharedSimulations() {
  static const std::unique_ptr<Simulations> sims = [] {
    std::vector<Candidate> all = DefaultCandidates();
    return std::make_unique<Simulations>(
        SimulateDesign(Base(), TableWith({}, kTruthSeed - 1), all, Params().simulate));
  }();
  return *sims;
}

DiagnoseResult DiagnoseTable(const Design& d) {
  const Simulations& s = SharedSimulations();
  if (!s.Matches(d)) throw std::runtime_error("fixture: the table's cells differ");
  return DiagnoseWith(d, s, Base(), Params());
}

TEST(Withheld, EachEffectAtTwoSizesIsNamedRecoveredAndShrinksTheHeldOutGap) {
  const std::vector<WithheldCase> cases = DefaultWithheldCases();
  ASSERT_EQ(cases.size(), 2 * sim::EffectRegistry().size());  // every effect, two sizes
  std::vector<CaseOutcome> outcomes;
  for (size_t i = 0; i < cases.size(); ++i) {
    const DiagnoseResult r = DiagnoseTable(TableWith({{cases[i].effect, cases[i].params}},
                                                     kTruthSeed + i));
    ASSERT_TRUE(r.success) << cases[i].effect << ": " << r.message;
    outcomes.push_back(Judge(r, cases[i]));
    const CaseOutcome& o = outcomes.back();
    EXPECT_TRUE(o.named) << o.truth.effect << " " << o.truth.size << ": rank " << o.rank
                         << ", first " << o.top;
    EXPECT_LE(o.max_rel_error, 0.2) << o.truth.effect << " " << o.truth.size;
    EXPECT_GE(o.shrink_heldout_pct, 70) << o.truth.effect << " " << o.truth.size;
  }
  std::printf("%s", FormatCases(outcomes).c_str());
}

TEST(Withheld, NoEffectOverTwentySeedsNamesNothing) {
  int named = 0;
  for (int i = 0; i < 20; ++i) {
    const DiagnoseResult r = DiagnoseTable(TableWith({}, 2000 + i));
    ASSERT_TRUE(r.success) << r.message;
    if (!r.steps.empty()) {
      ++named;
      std::printf("seed %d: %s named\n", 2000 + i, r.steps[0].effect.c_str());
    }
  }
  EXPECT_LE(named, 1) << "an effect was named in " << named << " of 20 tables without one";
}

TEST(Withheld, TwoEffectsAtOnceAreBothSelected) {
  const DiagnoseResult r = DiagnoseTable(TableWith(
      {{"disparity_offset", {{"delta_px", 0.2}}},
       {"edge_mixing", {{"width_px", 3}, {"strength", 0.6}}}},
      3000));
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_TRUE(r.Selected("disparity_offset"));
  EXPECT_TRUE(r.Selected("edge_mixing"));
  ASSERT_GE(r.selected.terms.size(), 2u);
  for (const TermFit& t : r.selected.terms) {
    const std::string& name = r.candidates[t.term.candidate].effect;
    if (name == "disparity_offset" && !t.term.per_scenario) {
      EXPECT_NEAR(t.values[0][0], 0.2, 0.04);
    }
  }
  EXPECT_GE(100 * (1 - r.selected_heldout.overall / r.baseline_heldout.overall), 70);
}

// The article's rows with a depth scale injected by its physics: every depth read (1 + s)
// times farther, so median, mean and plane_std scale exactly (valid_pct does not move). The
// fitted scale moves by s. (A disparity offset is not injected into a table this way: it moves
// the mean of a recording's samples by more than the mean's own transform, the far tail most.)
TEST(RealTable, AnInjectedDepthScaleMovesTheFittedScaleByItsSize) {
  const auto rows = io::ReadMetricsCsv(DEPTHBIAS_SOURCE_DIR "/config/data/paper_d455_outdoor.csv");
  ASSERT_EQ(rows.size(), 128u);
  const double s = 0.03;
  std::vector<records::PanelMetrics> injected = rows;
  for (auto& r : injected) {
    r.mean_m *= 1 + s;
    r.median_m *= 1 + s;
    r.plane_std_m *= 1 + s;
  }
  DiagnoseParams p = Params();
  p.candidates = "depth_scale,disparity_offset";
  p.max_selected = 0;
  Design a, b;
  std::string why;
  ASSERT_TRUE(BuildDesign(rows, &a, &why)) << why;
  ASSERT_TRUE(BuildDesign(injected, &b, &why)) << why;
  std::vector<Candidate> candidates;
  ASSERT_TRUE(SelectCandidates(p.candidates, &candidates, &why));
  const Simulations sims = SimulateDesign(Base(), a, candidates, p.simulate);
  const DiagnoseResult ra = DiagnoseWith(a, sims, Base(), p);
  const DiagnoseResult rb = DiagnoseWith(b, sims, Base(), p);
  ASSERT_TRUE(ra.success && rb.success) << ra.message << rb.message;
  const EffectResult* ea = ra.Effect("depth_scale");
  const EffectResult* eb = rb.Effect("depth_scale");
  ASSERT_TRUE(ea && eb);
  auto mean = [](const EffectResult* e) {
    double sum = 0;
    for (const auto& v : e->fit.values) sum += v[0];
    return sum / e->fit.values.size();
  };
  std::printf("fitted depth scale %.4f on the article's rows, %.4f with %.3f injected\n",
              mean(ea), mean(eb), s);
  EXPECT_NEAR(mean(eb) - mean(ea), s, 0.2 * s);
  EXPECT_GT(eb->delta_bic, ea->delta_bic);
}

}  // namespace
}  // namespace depthbias::gap
