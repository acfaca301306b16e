#pragma once
// Obstacle scenes rendered by the simulator (lib/sim) into depth frames, and a bias model with
// known weights, for the detector's tests.

#include <string>
#include <vector>

#include "model/bias_model.h"
#include "records/bias_weights.h"
#include "records/depth_frame.h"
#include "sim/stereo_sim.h"

namespace depthbias::detect::testing {

inline sim::Obstacle Person(double range_m, double azimuth_deg) {
  sim::Obstacle o;
  sim::ObstacleOfKind("person", &o);
  o.range_m = range_m;
  o.azimuth_deg = azimuth_deg;
  return o;
}

inline sim::Obstacle Bush(double range_m, double azimuth_deg) {
  sim::Obstacle o;
  sim::ObstacleOfKind("bush", &o);
  o.range_m = range_m;
  o.azimuth_deg = azimuth_deg;
  return o;
}

// A scene without a panel: the obstacles given, grass, a hedge at 22 m; the built-in D455
// (σ_d = 0.08 px) with the effects given.
inline sim::SimParams Scene(const std::vector<sim::Obstacle>& obstacles,
                            const std::vector<sim::EffectSpec>& effects = {},
                            double camera_height_m = 1.0, double pitch_deg = 0.0) {
  sim::SimParams p;
  p.protocol.scene.panel = false;
  p.protocol.scene.obstacles = obstacles;
  p.protocol.scene.hedge.distance_m = 22.0;
  p.protocol.scene.camera_height_m = camera_height_m;
  p.protocol.scene.camera_pitch_deg = pitch_deg;
  p.protocol.presets = {"HD"};
  p.protocol.emitters = {true};
  p.protocol.lights = {"daylight"};
  p.seed = 11;
  std::string why;
  if (!sim::BuildDepartures(effects, &p.departures, &why)) throw std::invalid_argument(why);
  return p;
}

// Frames 0..n−1 of the scene's one recording.
inline std::vector<records::DepthFrame> Render(const sim::SimParams& p, int n) {
  const std::vector<sim::Cell> cells = sim::MakeCells(p.protocol);
  const sim::StereoSim simulator(p, cells.at(0));
  std::vector<records::DepthFrame> frames(static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) simulator.Render(k, &frames[static_cast<size_t>(k)]);
  return frames;
}

// disp_scale weights (δ, k) of one scenario, daylight/HD, with a residual model and a near guard.
inline records::BiasWeights Weights(double delta_px, double scale, double placement_m = 0.02,
                                    double noise_per_m = 2e-4) {
  records::BiasWeights w;
  w.model = "disp_scale";
  w.focal_px = 640.0;
  w.baseline_m = 0.095;
  w.near_m = 5.0;
  w.full_m = 7.0;
  records::BiasWeightsGroup g;
  g.light = "daylight";
  g.preset = "HD";
  g.n = 32;
  g.names = {"delta_px", "k"};
  g.values = {delta_px, scale};
  g.covariance = {{1e-4, 0.0}, {0.0, 1e-6}};
  g.margin.known = true;
  g.margin.placement_m = placement_m;
  g.margin.noise_per_m = noise_per_m;
  w.groups.push_back(g);
  return w;
}

}  // namespace depthbias::detect::testing
