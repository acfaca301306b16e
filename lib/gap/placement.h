#pragma once
// Placement and session as a variance component. Every test point (light, distance, angle) is
// one panel placement, shared by all its recordings (both presets, emitter on and off): a tape
// error, a stand set a little off, a change of light between sessions moves all of them
// together. That is neither replicate noise (the emitter twins share it, so their difference
// cannot show it) nor a camera effect (it does not repeat from one test point to the next).
//
// Per compared metric k the residual y − sim (the base simulation) of a recording i at test
// point t is modelled as
//   y − sim = X·β + u_t + e_i,   u_t ~ N(0, τ_k(D_t)²),   e_i ~ N(0, σ_i²)              (1)
// with σ_i the replicate noise (noise.h, known), X the fixed effects every camera law of the
// registry lives in (main effects and two-factor interactions of light, distance, angle,
// preset and emitter, but light × angle: no law of the registry makes the light change how the
// angle acts, while one session's stand set off at one angle does; and distance × angle as the
// two laws D·(1 − cos α) and D²·(1 − cos α): how a law acting through the panel's depth D·cos α,
// or its square, departs from additive in distance and angle), and τ the placement scatter's law
// in the test point's distance D:
//   median bias:  τ(D) = a + b·D  [m]   (a: tape and stand, independent of range; b·D: a
//                 distance meaning or aiming error, and depth read through a panel set a
//                 fraction of a degree off, which grow with range)
//   other metrics: τ(D) = a · (D / 10 m)^e, e the metric's noise exponent (one parameter)
// estimated by restricted maximum likelihood (REML: the fixed effects' degrees of freedom are
// not taken for scatter). What of light × distance × angle no two-factor law explains is counted
// as placement, so a camera law of the registry stays a fixed effect and is judged against τ,
// not absorbed by it.
//
// Heavy tail: a test point's departure (its recordings' mean residual about X·β) is read
// against the law, and against the departures' own robust scale where a tail has inflated the
// law (1.4826·median |z| below its own chance low). The point farthest beyond p < alpha / test
// points (Bonferroni), also at the largest scatter the law's restricted likelihood allows at its
// distance (a law read from few test points is loose; a flagged point's z is reported there), is
// flagged and given a free variance in the estimate (its mean informs neither β nor the law; its
// preset and emitter contrasts still do), the fit is made again, and the search grows one point
// at a time until no point joins: a misplaced point pulls its distance's effects, and its
// neighbours may look beyond the law only while it is in. A flagged point's departure is then
// read as predicted from the others, and it gets that departure as its scatter, so that one
// misplaced panel is reported as such and never taken for a camera effect. Distance × angle is
// two laws, not a table of its own: a table would also take up what one test point does alone,
// and with two lights leave a point only its contrast with its partner of the other light (a
// misplaced point and its partner would depart together, the other way, and which of them was
// misplaced could not be told).

#include <string>
#include <vector>

#include "gap/design.h"
#include "gap/noise.h"
#include "gap/simulations.h"

namespace depthbias::gap {

// Test point of every cell (light, distance, angle), numbered in first-seen order.
std::vector<int> TestPoints(const Design& design, int* num_points);

struct PlacementEstimate {
  std::vector<int> point;                 // [cell] test point
  int num_points = 0;
  std::vector<double> point_distance_m;   // [point]
  std::vector<double> point_angle_deg;
  std::vector<std::string> point_light;
  // Per compared metric k: the law τ_k(D) = a_k·f(D) + b_k·D, f = 1 for the median bias,
  // (D / 10 m)^e for the others (b = 0).
  std::vector<double> a, b;
  // The floor of a spread's scatter. A panel standing u off along its line of sight moves the
  // log of a spread (plane_std, temporal_std: ∝ Z² for a free spread) by s·u, s its sensitivity
  // measured on the simulation (Simulations::moved: the base with every panel placed further
  // by a known share of its distance; mean over the cells at that distance), so their scatter
  // is at least |s(D)|·τ_median(D). Their own REML reads 0.014–0.045 where panels placed 2 % off
  // give 0.04, and 0 on some tables without effect (z to −26 at 4 m on one with the dithered
  // lattices). The sensitivity, not 2/Z: in the region the window draws, plane_std grows
  // slower than Z² beyond 12 m (at 17.1 m it is 1.02 times its 16 m value, Z² says 1.14).
  std::vector<int> floor_of;                  // [k] the median's index, −1: no floor
  std::vector<double> floor_distance_m;       // the distances the sensitivity is known at
  std::vector<std::vector<double>> sensitivity;  // [k][distance] per metre
  // [k] the share of the median's scatter a spread reads as the panel's displacement (0: none)
  std::vector<double> coupling;
  std::vector<int> points_used;           // [k] test points the law was estimated from
  std::vector<std::vector<double>> departure;    // [k][point] mean residual about X·β
  std::vector<std::vector<double>> departure_z;  // [k][point] over its sd under the law
  std::vector<std::vector<char>> flagged;        // [k][point] beyond the law (Bonferroni)
  std::vector<std::vector<double>> tau;          // [k][point] scatter used in the covariance
  // A spread's scatter per recording, where the floor is read per scenario: one displacement
  // of the panel moves each preset's and light's spread by its own sensitivity (the simulator's
  // daylight cells at 12 m: 0.16 per metre for HA, 0.03 for HD, where HD's plane_std nears the
  // panel's in-plane spread), so the recordings of one test point share it with loadings that
  // differ (Tau). [k][cell]; empty for a metric without a floor.
  std::vector<std::vector<double>> tau_cell;

  // The share of compared metric k's scatter at test point t that is the panel's displacement
  // along its line of sight, the one the median reads (signed as the metric moves with it): 1
  // for the median at its law (less where a flagged point's scatter is its departure), a
  // spread's floor over its scatter (its sensitivity times the median's law, Floor) times its
  // coupling, 0 for a metric without a floor. Two metrics' scatters at one test point
  // correlate as the product of their shares (fit.h, (2)).
  double Shared(int k, int metric, int t) const;
  // The law at distance D for compared metric k (metric: its Metric value), its floor included.
  double Law(int k, int metric, double distance_m) const;
  // The floor of compared metric k's scatter at distance D (0: none).
  double Floor(int k, double distance_m) const;
  // Its sensitivity to the panel's displacement at the nearest distance it is known at, per
  // metre (0: no floor).
  double Sensitivity(int k, double distance_m) const;
  double Tau(int k, int cell) const {
    if (tau.empty()) return 0.0;
    return tau_cell[k].empty() ? tau[k][point[cell]] : tau_cell[k][cell];
  }
  bool empty() const { return tau.empty(); }
};

// The share of the median's scatter each spread reads as the panel's displacement
// (PlacementEstimate::coupling): the slope of its test points' departures on its sensitivity
// times the median's, through 0, over the test points neither flags, within [0, 1] (on the
// article's rows, log plane_std: 0.62). From the departures and floors of `pe`.
void EstimateCoupling(PlacementEstimate* pe);

// The scatter of every compared metric, from the cells marked in `train` (recordings whose
// residual is finite). alpha: the significance at which a test point is flagged.
PlacementEstimate EstimatePlacement(const Design& design, const Simulations& sims,
                                    const NoiseEstimate& noise, const std::vector<char>& train,
                                    double alpha);

}  // namespace depthbias::gap
