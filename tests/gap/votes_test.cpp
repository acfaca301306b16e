// What the outer folds choose (gap/votes.h), on folds written by hand: the votes, the rival the
// keep rule sets against an effect the table selected, and the pairs the folds split between.
#include "gap/votes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace depthbias::gap {
namespace {

const double kNeed[2] = {10, 30};  // DiagnoseParams' floors of an effect's own part, in %

// One outer fold: its selection, each effect with its own part (share of the fold's calibrated
// Σz² it brings back when left out) and that share in the metrics it moves.
struct Pick {
  std::string effect;
  double part;
  double moved;
};

NestedFold Fold(const std::vector<Pick>& picks, bool simulated = true) {
  NestedFold f;
  f.simulated = simulated;
  f.simulated_calibrated_sq = 200;
  for (const Pick& p : picks) {
    f.selected.push_back(p.effect);
    f.effect_gain_simulated.push_back(200 * p.part);
    f.effect_share_moved.push_back(p.moved);
  }
  return f;
}

Nested Folds(std::vector<NestedFold> folds) {
  Nested n;
  n.run = true;
  n.folds = std::move(folds);
  return n;
}

std::vector<SelectionStep> Steps(const std::vector<std::string>& effects) {
  std::vector<SelectionStep> steps;
  for (const std::string& e : effects) steps.push_back(SelectionStep{e});
  return steps;
}

const std::vector<Confounded> kOffsetScale = {{"disparity_offset", "depth_scale", -0.8}};

TEST(Votes, AnEffectsOwnPartIsAveragedOverEveryFold) {
  const Nested n = Folds({Fold({{"a", 0.2, 0.5}}), Fold({{"a", 0.2, 0.1}, {"b", 0.05, 0.1}}),
                          Fold({{"b", 0.3, 0.2}}), Fold({})});
  const FoldVote a = VoteOf(n, "a", kNeed);
  EXPECT_EQ(a.count, 2);
  EXPECT_NEAR(a.pct[0], 10, 1e-9);  // (20 + 20) / 4 folds, not / 2
  EXPECT_NEAR(a.pct[1], 15, 1e-9);
  EXPECT_TRUE(a.earns);
  const FoldVote b = VoteOf(n, "b", kNeed);
  EXPECT_EQ(b.count, 2);
  EXPECT_NEAR(b.pct[0], 8.75, 1e-9);
  EXPECT_FALSE(b.earns) << "8.75 % and 7.5 %: below both floors";
  const FoldVote c = VoteOf(n, "c", kNeed);
  EXPECT_EQ(c.count, 0);
  EXPECT_FALSE(c.earns) << "no fold selects it";
  // A fold selecting it that was not simulated: its part is unknown, the count decides.
  const Nested m = Folds({Fold({{"a", 0.01, 0.01}}, false), Fold({{"a", 0.01, 0.01}}), Fold({}),
                          Fold({})});
  const FoldVote u = VoteOf(m, "a", kNeed);
  EXPECT_FALSE(u.known);
  EXPECT_TRUE(std::isnan(u.pct[0]));
  EXPECT_TRUE(u.earns);
}

// The table keeps the scale; the folds choose the offset as often, one of them without the
// scale and carrying its own part there: the offset is the scale's rival.
TEST(Votes, AKeptEffectsRivalIsChosenAsOftenAndNotOnlyBesideIt) {
  const Nested n = Folds({Fold({{"depth_scale", 0.4, 0.6}}),
                          Fold({{"disparity_offset", 0.25, 0.4}}),
                          Fold({{"depth_scale", 0.2, 0.5}, {"disparity_offset", 0.01, 0.02}}),
                          Fold({})});
  FoldVote w = VoteOf(n, "depth_scale", kNeed);
  ASSERT_TRUE(w.earns);
  FindRival(n, kOffsetScale, Steps({"depth_scale"}), "depth_scale", kNeed, &w);
  EXPECT_EQ(w.rival, "disparity_offset");
  EXPECT_EQ(w.rival_count, 2);
  EXPECT_NEAR(w.rival_r, -0.8, 1e-12);
  // The offset only ever beside the scale: a rider, no rival.
  const Nested rider = Folds({Fold({{"depth_scale", 0.4, 0.6}, {"disparity_offset", 0.3, 0.4}}),
                              Fold({{"depth_scale", 0.3, 0.6}, {"disparity_offset", 0.3, 0.4}}),
                              Fold({}), Fold({})});
  FoldVote v = VoteOf(rider, "depth_scale", kNeed);
  ASSERT_TRUE(v.earns);
  FindRival(rider, kOffsetScale, Steps({"depth_scale"}), "depth_scale", kNeed, &v);
  EXPECT_TRUE(v.rival.empty()) << v.rival;
  // Chosen once against the scale's twice: the folds prefer the scale.
  const Nested fewer = Folds({Fold({{"depth_scale", 0.4, 0.6}}), Fold({{"depth_scale", 0.4, 0.6}}),
                              Fold({{"disparity_offset", 0.4, 0.6}}), Fold({})});
  FoldVote x = VoteOf(fewer, "depth_scale", kNeed);
  FindRival(fewer, kOffsetScale, Steps({"depth_scale"}), "depth_scale", kNeed, &x);
  EXPECT_TRUE(x.rival.empty()) << x.rival;
  // Weakly correlated, or selected by the table too: no rival.
  FoldVote y = VoteOf(n, "depth_scale", kNeed);
  FindRival(n, {{"disparity_offset", "depth_scale", 0.45}}, Steps({"depth_scale"}), "depth_scale",
            kNeed, &y);
  EXPECT_TRUE(y.rival.empty()) << y.rival;
  FoldVote z = VoteOf(n, "depth_scale", kNeed);
  FindRival(n, kOffsetScale, Steps({"depth_scale", "disparity_offset"}), "depth_scale", kNeed, &z);
  EXPECT_TRUE(z.rival.empty()) << z.rival;
}

// The table selects the scale, which one fold of four chooses, and drops it; three folds choose
// the offset, alone and carrying their gap: the table's choice between the two is not the
// folds', and the offset is named beside it.
TEST(Votes, ADroppedEffectsRivalIsChosenByMoreFoldsAndEarns) {
  const Nested n = Folds({Fold({{"depth_scale", 0.3, 0.5}}), Fold({{"disparity_offset", 0.3, 0.5}}),
                          Fold({{"disparity_offset", 0.2, 0.4}}),
                          Fold({{"disparity_offset", 0.25, 0.5}})});
  FoldVote w = VoteOf(n, "depth_scale", kNeed);
  ASSERT_FALSE(w.earns);
  FindRival(n, kOffsetScale, Steps({"depth_scale"}), "depth_scale", kNeed, &w);
  EXPECT_EQ(w.rival, "disparity_offset");
  EXPECT_EQ(w.rival_count, 3);
  // Three folds, but too little of their gap: the offset does not earn, no rival.
  const Nested weak = Folds({Fold({{"depth_scale", 0.3, 0.5}}),
                             Fold({{"disparity_offset", 0.05, 0.1}}),
                             Fold({{"disparity_offset", 0.05, 0.1}}),
                             Fold({{"disparity_offset", 0.05, 0.1}})});
  FoldVote v = VoteOf(weak, "depth_scale", kNeed);
  FindRival(weak, kOffsetScale, Steps({"depth_scale"}), "depth_scale", kNeed, &v);
  EXPECT_TRUE(v.rival.empty()) << v.rival;
  // The scale dropped for its own part (two folds of four, 1 % of their gap), not for its
  // folds: no contest of folds, though three folds choose the offset and it earns.
  const Nested small = Folds({Fold({{"depth_scale", 0.02, 0.02}}),
                              Fold({{"depth_scale", 0.02, 0.02}, {"disparity_offset", 0.5, 0.5}}),
                              Fold({{"disparity_offset", 0.5, 0.5}}),
                              Fold({{"disparity_offset", 0.5, 0.5}})});
  FoldVote y = VoteOf(small, "depth_scale", kNeed);
  ASSERT_FALSE(y.earns);
  ASSERT_TRUE(VoteOf(small, "disparity_offset", kNeed).earns);
  FindRival(small, kOffsetScale, Steps({"depth_scale"}), "depth_scale", kNeed, &y);
  EXPECT_TRUE(y.rival.empty()) << y.rival;
  // Two rivals chosen by as many folds: the more correlated one.
  const Nested two = Folds({Fold({{"depth_scale", 0.3, 0.5}}),
                            Fold({{"disparity_offset", 0.3, 0.5}, {"range_vs_depth", 0.3, 0.5}}),
                            Fold({{"disparity_offset", 0.3, 0.5}, {"range_vs_depth", 0.3, 0.5}}),
                            Fold({{"disparity_offset", 0.3, 0.5}, {"range_vs_depth", 0.3, 0.5}})});
  for (const auto& order : {std::vector<Confounded>{{"disparity_offset", "depth_scale", -0.6},
                                                    {"depth_scale", "range_vs_depth", 0.9}},
                            std::vector<Confounded>{{"depth_scale", "range_vs_depth", 0.9},
                                                    {"disparity_offset", "depth_scale", -0.6}}}) {
    FoldVote t = VoteOf(two, "depth_scale", kNeed);
    FindRival(two, order, Steps({"depth_scale"}), "depth_scale", kNeed, &t);
    EXPECT_EQ(t.rival, "range_vs_depth");
    EXPECT_NEAR(t.rival_r, 0.9, 1e-12);
  }
}

TEST(Votes, FoldsSplitBetweenTwoLawsOnlyWhenEveryFoldChoosesOne) {
  auto sizes = [](const std::vector<std::string>& effects) {
    return std::vector<std::string>(effects.size(), "size");
  };
  const Nested n = Folds({Fold({{"disparity_offset", 0.3, 0.5}}), Fold({{"depth_scale", 0.3, 0.5}}),
                          Fold({{"disparity_offset", 0.2, 0.4}}),
                          Fold({{"depth_scale", 0.2, 0.4}})});
  const std::vector<Ambiguity> split = FoldSplits(n, kOffsetScale, {}, {}, kNeed, sizes);
  ASSERT_EQ(split.size(), 1u);
  EXPECT_EQ(split[0].effects, (std::vector<std::string>{"disparity_offset", "depth_scale"}));
  EXPECT_NE(split[0].why.find("offset in 2, depth_scale in 2 of 4"), std::string::npos)
      << split[0].why;
  // One fold chooses neither; one of them is kept; the pair is already named: none.
  const Nested gap = Folds({Fold({{"disparity_offset", 0.3, 0.5}}),
                            Fold({{"depth_scale", 0.3, 0.5}}),
                            Fold({{"disparity_offset", 0.2, 0.4}}), Fold({})});
  EXPECT_TRUE(FoldSplits(gap, kOffsetScale, {}, {}, kNeed, sizes).empty());
  EXPECT_TRUE(FoldSplits(n, kOffsetScale, Steps({"depth_scale"}), {}, kNeed, sizes).empty());
  EXPECT_TRUE(FoldSplits(n, kOffsetScale, {}, split, kNeed, sizes).empty());
  // Their own part too small where chosen: none.
  const Nested weak = Folds({Fold({{"disparity_offset", 0.03, 0.1}}),
                             Fold({{"depth_scale", 0.03, 0.1}}),
                             Fold({{"disparity_offset", 0.03, 0.1}}),
                             Fold({{"depth_scale", 0.03, 0.1}})});
  EXPECT_TRUE(FoldSplits(weak, kOffsetScale, {}, {}, kNeed, sizes).empty());
}

}  // namespace
}  // namespace depthbias::gap
