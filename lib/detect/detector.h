#pragma once
// The obstacle detector: one depth frame → the obstacles in it, each with its raw range, its
// range corrected by the bias model (model::ScenarioModel, the same code correct_depth uses),
// the predictive σ there, a safe range (min(raw, corrected − k·σ)) and a zone from the
// machine's stopping distance; a frame that shows too little is blind and clears nothing.
//
// Per frame, the stages of stages.h: deproject one pixel per stride block (rays computed once);
// voxel grid; ground removed by RANSAC with a normal constraint (PCL); Euclidean clusters whose
// tolerance grows with range as the stereo noise does (PCL k-d tree); clusters above a size are
// obstacles, measured on their own points (not the voxels), corrected and zoned.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "camera/intrinsics.h"
#include "detect/noise.h"
#include "detect/params.h"
#include "model/bias_model.h"
#include "records/depth_frame.h"

namespace depthbias::detect {

enum class Zone { kStop, kSlow, kClear };
std::string ZoneName(Zone zone);  // "stop", "slow", "clear"
// stop: safe range ≤ S; slow: ≤ S + slow_margin_m; clear beyond (S = zones.StoppingDistanceM()).
Zone ZoneFor(double safe_range_m, const ZoneParams& zones);

struct DetectedObstacle {
  Eigen::Vector3d centroid_m = Eigen::Vector3d::Zero();  // mean of its points, camera frame
  double azimuth_deg = 0.0;        // atan2(x, z) of the centroid, + right
  double off_axis_deg = 0.0;       // radial angle of the centroid's ray (the model's α)
  double depth_m = 0.0;            // median Z of its points (the model's Z)
  double range_m = 0.0;            // median Euclidean range of its points (raw)
  double corrected_range_m = 0.0;  // the model's corrected range at (Z, α): CorrectedM
  double std_m = 0.0;              // √(model σ at (Z, α)² + this frame's median noise²)
  double safe_range_m = 0.0;       // min(range_m, corrected − k·σ) (params.safe_beyond_raw: the
                                   // latter alone)
  bool near_guarded = false;       // the model left (part of) its correction out (near guard)
  Zone zone = Zone::kClear;
  int points = 0;                  // cloud points
  int voxels = 0;
  double height_m = 0.0;           // extent along the ground's normal (image vertical if none)
  double width_m = 0.0;            // horizontal extent across the line of sight
};

struct FrameDetections {
  bool success = false;
  std::string message;             // why not (a frame of another size)
  std::uint64_t frame = 0;         // index of the frame in the recording, from 0
  double timestamp_s = 0.0;        // the frame's device timestamp
  // Valid samples (a depth within the cloud's ranges) as a share of the sampled pixels [%];
  // below cloud.min_valid_pct the frame is blind: "I saw nothing" is not "there is nothing".
  double valid_pct = 0.0;
  bool blind = false;
  // The frame's zone: the most severe of its obstacles', clear when there are none; stop when
  // the frame is blind (and then every obstacle in it is stop too: nothing is cleared on it).
  Zone zone = Zone::kClear;
  std::vector<DetectedObstacle> obstacles;  // nearest first
  double disparity_noise_px = 0.0; // σ_d of this frame's margin (the reading's noise)
  NoiseSource disparity_noise_from = NoiseSource::kConfig;  // where that σ_d came from
  // Diagnostics.
  int samples = 0;                 // sampled pixels (one per stride block)
  int cloud_points = 0;
  int voxels = 0;
  bool ground_found = false;
  Eigen::Vector4d ground = Eigen::Vector4d::Zero();  // n·p + d = 0, camera on the + side
  int ground_inliers = 0;
  int ransac_iterations = 0;
  int clusters = 0;                // before the size test
};

class ObstacleDetector {
 public:
  // Throws std::invalid_argument for invalid parameters or intrinsics. `scenario` must outlive
  // the detector.
  ObstacleDetector(const camera::Intrinsics& intrinsics, const DetectorParams& params,
                   const model::ScenarioModel& scenario);
  ~ObstacleDetector();
  ObstacleDetector(const ObstacleDetector&) = delete;
  ObstacleDetector& operator=(const ObstacleDetector&) = delete;

  // Frame `index` of a recording. Not thread-safe (the detector keeps its buffers).
  FrameDetections Detect(const records::DepthFrame& frame, std::uint64_t index);

  const DetectorParams& params() const { return params_; }

  // σ_d of the margin's reading noise [px]: cluster.disparity_noise_px until set (the app sets
  // the weights' or the recording's own, noise.h), and where it came from. Throws
  // std::invalid_argument unless finite and > 0.
  void SetDisparityNoisePx(double sigma_px, NoiseSource source = NoiseSource::kRecording);
  double disparity_noise_px() const { return sigma_d_px_; }
  NoiseSource disparity_noise_from() const { return sigma_d_from_; }
  // The temporal spread at the obstacles of consecutive frames seen so far (frames whose
  // indices follow each other), and a fresh start.
  const TemporalNoise& temporal_noise() const;
  void ResetTemporalNoise();

 private:
  struct Impl;
  DetectorParams params_;
  double sigma_d_px_ = 0.0;
  NoiseSource sigma_d_from_ = NoiseSource::kConfig;
  std::unique_ptr<Impl> impl_;
};

}  // namespace depthbias::detect
