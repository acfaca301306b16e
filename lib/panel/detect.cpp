#include "panel/detect.h"

#include "records/number_text.h"
#include "panel/panel_fit.h"

#include <algorithm>
#include <cmath>
#include <numeric>

// PCL's templates are instantiated here from its headers, so that only libpcl_common is linked:
// loading libpcl_segmentation and the libraries it drags in (features, filters, ...) costs
// about 0.1 s of symbol relocation at every start of a program.
#define PCL_NO_PRECOMPILE
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/ransac.h>
#include <pcl/sample_consensus/sac_model_perpendicular_plane.h>
#include <pcl/sample_consensus/sac_model_plane.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>

#include "common/seeded_ransac.h"

namespace depthbias::panel {
namespace {

constexpr double kDegToRad = M_PI / 180.0;
constexpr double kRadToDeg = 180.0 / M_PI;

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

using common::CountingRansac;
using common::Seeded;

struct RansacOut {
  bool ok = false;
  metrics::Plane plane;
  pcl::Indices inliers;
  int iterations = 0;
};

RansacOut RunRansac(const pcl::SampleConsensusModel<pcl::PointXYZ>::Ptr& model,
                    double threshold_m, const PanelParams& p) {
  RansacOut out;
  CountingRansac ransac(model, threshold_m);
  ransac.setMaxIterations(p.ransac_max_iterations);
  ransac.setProbability(p.ransac_probability);
  if (!ransac.computeModel()) return out;
  out.iterations = ransac.iterations();
  ransac.getInliers(out.inliers);
  Eigen::VectorXf coeff;
  ransac.getModelCoefficients(coeff);
  if (coeff.size() != 4) return out;
  Eigen::Vector3d n(coeff[0], coeff[1], coeff[2]);
  const double len = n.norm();
  if (!(len > 0)) return out;
  out.plane.normal = n / len;
  out.plane.offset_m = coeff[3] / len;
  if (out.plane.offset_m < 0) {
    out.plane.normal = -out.plane.normal;
    out.plane.offset_m = -out.plane.offset_m;
  }
  out.ok = true;
  return out;
}

// Depth noise of one sample at depth Z: σ_Z = Z²·σ_d / (f·B).
double DepthSigma(double depth_m, double focal_px, const PanelParams& p) {
  return depth_m * depth_m * p.expected_subpixel_rms_px / (focal_px * p.baseline_m);
}

// One point of the detection cloud: the best-observed pixel of a block.
struct CloudPoint {
  std::uint32_t pixel;
  Eigen::Vector3d p;
};

}  // namespace

DepthAccumulator::DepthAccumulator(int width, int height)
    : width_(width),
      height_(height),
      n_(static_cast<std::size_t>(width) * height, 0),
      sum_(static_cast<std::size_t>(width) * height, 0) {}

void DepthAccumulator::Add(const records::DepthFrame& frame) {
  depth_units_m_ = frame.depth_units_m;
  if (frames_ > 0 && frames_ % 65535 == 0) {  // a 32-bit sum holds 65535 frames of 16-bit counts
    carry_.resize(sum_.size(), 0.0);
    for (std::size_t i = 0; i < sum_.size(); ++i) {
      carry_[i] += sum_[i];
      sum_[i] = 0;
    }
  }
  ++frames_;
  const std::uint16_t* c = frame.counts.data();
  std::uint32_t* n = n_.data();
  std::uint32_t* s = sum_.data();
  const std::size_t size = n_.size();
  for (std::size_t i = 0; i < size; ++i) {
    const std::uint32_t v = c[i];
    n[i] += v != 0;
    s[i] += v;
  }
}

PanelDetection DetectPanel(const metrics::RayTable& rays, const DepthAccumulator& acc,
                           const PanelParams& p, const SearchWindow& window) {
  PanelDetection det;
  det.frames = acc.frames();
  const int w = acc.width(), h = acc.height();
  const double focal_px = rays.intrinsics().fx;
  const int block = p.block_px > 0 ? p.block_px : std::max(1, w / 320);
  det.block_px = block;

  // 1. Detection cloud: per block, the pixel with the most samples.
  std::vector<CloudPoint> pts;
  for (int by = 0; by < h; by += block) {
    for (int bx = 0; bx < w; bx += block) {
      std::uint32_t best = 0, best_n = 0;
      for (int v = by; v < std::min(h, by + block); ++v) {
        for (int u = bx; u < std::min(w, bx + block); ++u) {
          const std::uint32_t i = static_cast<std::uint32_t>(v * w + u);
          if (acc.Count(i) > best_n) {
            best_n = acc.Count(i);
            best = i;
          }
        }
      }
      if (best_n == 0) continue;
      const double z = acc.MeanDepth(best);
      if (z < p.min_depth_m || z > p.max_depth_m) continue;
      pts.push_back({best, z * rays.Ray(best)});
    }
  }
  det.cloud_points = static_cast<int>(pts.size());
  if (static_cast<int>(pts.size()) < p.min_cluster_points) {
    det.why_not = "too few pixels with depth (" + std::to_string(pts.size()) + " blocks)";
    return det;
  }
  Cloud::Ptr cloud(new Cloud);
  cloud->resize(pts.size());
  for (std::size_t k = 0; k < pts.size(); ++k)
    (*cloud)[k] = pcl::PointXYZ(static_cast<float>(pts[k].p.x()), static_cast<float>(pts[k].p.y()),
                                static_cast<float>(pts[k].p.z()));
  pcl::Indices all(pts.size());
  std::iota(all.begin(), all.end(), 0);

  // 2. Ground: RANSAC plane whose normal is within ground_max_angle_deg of the camera's −y,
  //    refined by least squares on its inliers.
  std::vector<char> keep(pts.size(), 1);
  Eigen::Vector3d up_hint(0, -1, 0);
  if (p.remove_ground) {
    auto model = std::make_shared<Seeded<pcl::SampleConsensusModelPerpendicularPlane<pcl::PointXYZ>>>(
        cloud, all, p.seed);
    model->setAxis(Eigen::Vector3f(0, 1, 0));
    model->setEpsAngle(p.ground_max_angle_deg * kDegToRad);
    RansacOut g = RunRansac(model, p.ground_distance_m, p);
    det.ransac_iterations += g.iterations;
    if (g.ok && g.inliers.size() >= p.min_ground_fraction * pts.size()) {
      metrics::Plane ground = g.plane;
      for (int it = 0; it < 2; ++it) {
        metrics::PlaneMoments m;
        for (std::size_t k = 0; k < pts.size(); ++k)
          if (std::fabs(ground.Distance(pts[k].p)) < p.ground_distance_m) m.Add(pts[k].p);
        const metrics::PlaneFit f = metrics::FitPlane(m);
        if (f.ok) ground = f.plane;
      }
      det.ground_found = true;
      det.ground = ground;
      for (std::size_t k = 0; k < pts.size(); ++k) {
        // Remove the ground and whatever lies below it (the far side from the camera).
        if (ground.Distance(pts[k].p) < p.ground_distance_m) {
          keep[k] = 0;
          ++det.ground_inliers;
        }
      }
      up_hint = ground.normal;  // toward the camera, which stands above the ground
    }
  }

  // 3. Clusters of the remaining points, in (x/z, y/z, k·ln z): neighbours within a fixed angle
  //    and a fixed relative depth, whatever their distance.
  Cloud::Ptr scaled(new Cloud);
  std::vector<std::size_t> back;
  const double depth_scale = p.cluster_angle_rad / p.cluster_relative_depth;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    if (!keep[k]) continue;
    const Eigen::Vector3d& q = pts[k].p;
    scaled->push_back(pcl::PointXYZ(static_cast<float>(q.x() / q.z()),
                                    static_cast<float>(q.y() / q.z()),
                                    static_cast<float>(depth_scale * std::log(q.z()))));
    back.push_back(k);
  }
  if (static_cast<int>(scaled->size()) < p.min_cluster_points) {
    det.why_not = "nothing but ground in view";
    return det;
  }
  std::vector<pcl::PointIndices> clusters;
  {
    pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
    tree->setInputCloud(scaled);
    pcl::EuclideanClusterExtraction<pcl::PointXYZ> ec;
    ec.setClusterTolerance(p.cluster_angle_rad);
    ec.setMinClusterSize(p.min_cluster_points);
    ec.setMaxClusterSize(static_cast<int>(scaled->size()));
    ec.setSearchMethod(tree);
    ec.setInputCloud(scaled);
    ec.extract(clusters);  // sorted largest first
  }
  det.clusters = static_cast<int>(clusters.size());
  if (clusters.empty()) {
    det.why_not = "no cluster of at least " + std::to_string(p.min_cluster_points) +
                  " points off the ground";
    return det;
  }

  // 4. Planes in each cluster; on each, the panel's known size fitted where the evidence says a
  //    solid, free-standing panel stands (panel_fit.h), and scored as the panel.
  struct Found {
    WindowFit fit;
    double plane_rms_m = 0;
  };
  std::vector<Found> found;
  const double nominal_w = p.panel_width_m, nominal_h = p.panel_height_m;
  const metrics::Plane* ground = det.ground_found ? &det.ground : nullptr;
  for (std::size_t c = 0; c < clusters.size() && static_cast<int>(c) < p.max_clusters; ++c) {
    pcl::Indices remaining;
    std::vector<double> depths;
    for (int j : clusters[c].indices) {
      remaining.push_back(static_cast<int>(back[j]));
      depths.push_back(pts[back[j]].p.z());
    }
    std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
    const double z_med = depths[depths.size() / 2];
    const double thr = p.plane_sigma_k * DepthSigma(z_med, focal_px, p) + p.plane_distance_m;
    for (int plane_no = 0; plane_no < p.max_planes_per_cluster &&
                           static_cast<int>(remaining.size()) >= p.min_cluster_points;
         ++plane_no) {
      auto model = std::make_shared<Seeded<pcl::SampleConsensusModelPlane<pcl::PointXYZ>>>(
          cloud, remaining, p.seed + 7919u * (c + 1) + plane_no);
      RansacOut r = RunRansac(model, thr, p);
      det.ransac_iterations += r.iterations;
      if (!r.ok || static_cast<int>(r.inliers.size()) < p.min_cluster_points) break;
      // Least-squares refinement on the inliers, then the inliers of the refined plane.
      metrics::PlaneMoments m;
      for (int k : r.inliers) m.Add(pts[k].p);
      const metrics::PlaneFit lsq = metrics::FitPlane(m);
      const metrics::Plane plane = lsq.ok ? lsq.plane : r.plane;
      Eigen::Vector3d seed = Eigen::Vector3d::Zero();
      int inliers = 0;
      pcl::Indices rest;
      for (int k : remaining) {
        if (std::fabs(plane.Distance(pts[k].p)) < thr) {
          seed += pts[k].p;
          ++inliers;
        } else {
          rest.push_back(k);
        }
      }
      if (inliers < p.min_cluster_points) break;
      remaining.swap(rest);
      seed /= inliers;

      PanelCandidate cand;
      cand.cluster = static_cast<int>(c);
      cand.inliers = inliers;
      Found f;
      f.fit = FitAndRefinePanel(rays, acc, plane, up_hint, ground, seed, p, &f.plane_rms_m);
      if (!f.fit.success) {
        cand.rejected = f.fit.message;
        det.candidates.push_back(cand);
        found.push_back(std::move(f));
        continue;
      }
      const metrics::PanelRectangle& rect = f.fit.rect;
      const WindowEvidence& ev = f.fit.evidence;
      cand.width_m = ev.covered_width_m;
      cand.height_m = ev.covered_height_m;
      cand.range_m = rect.center_m.norm();
      cand.off_axis_deg = std::acos(rect.center_m.z() / cand.range_m) * kRadToDeg;
      cand.facing_deg =
          std::acos(std::min(1.0, rect.plane.normal.dot(-rect.center_m) / cand.range_m)) *
          kRadToDeg;
      cand.evidence = ev;
      cand.see_through = ev.SeeThrough();
      cand.ring_share = ev.RingShare();
      const double coverage = std::min(cand.width_m / nominal_w, cand.height_m / nominal_h);
      if (coverage < p.min_coverage) {
        cand.rejected = "its pixels cover only " + records::NumberText(cand.width_m) + " x " +
                        records::NumberText(cand.height_m) + " m of the panel's size";
      } else if (cand.see_through > p.max_see_through) {
        cand.rejected = "the background shows through " + records::NumberText(100 * cand.see_through) +
                        " % of it: not a solid panel";
      } else if (ev.occupied_sides >= 3) {
        cand.rejected = "the plane continues around it (" + records::NumberText(100 * cand.ring_share) +
                        " % of a ring, " + std::to_string(ev.occupied_sides) +
                        " sides): part of a larger surface";
      } else if (cand.facing_deg > p.max_facing_angle_deg) {
        cand.rejected = "does not face the camera";
      }
      const double rms_thr = p.plane_sigma_k * DepthSigma(cand.range_m, focal_px, p) +
                             p.plane_distance_m;
      cand.cost = 2.0 * cand.see_through + cand.ring_share + 0.5 * (1.0 - std::min(1.0, coverage)) +
                  0.2 * cand.facing_deg / p.max_facing_angle_deg +
                  0.2 * std::min(1.0, f.plane_rms_m / rms_thr);
      if (p.use_search_window && window.known()) {
        if (std::isfinite(window.distance_m)) {
          const double dd = std::fabs(cand.range_m - window.distance_m);
          const double lim = p.window_distance_frac * window.distance_m + p.window_distance_m;
          if (dd > lim && cand.rejected.empty()) cand.rejected = "outside the distance window";
          cand.cost += 0.5 * dd / lim;
        }
        if (std::isfinite(window.angle_deg)) {
          const double da = std::fabs(cand.off_axis_deg - std::fabs(window.angle_deg));
          if (da > p.window_angle_deg && cand.rejected.empty())
            cand.rejected = "outside the angle window";
          cand.cost += 0.5 * da / p.window_angle_deg;
        }
      }
      det.candidates.push_back(cand);
      found.push_back(std::move(f));
    }
  }
  int best = -1;
  for (std::size_t k = 0; k < det.candidates.size(); ++k) {
    if (!det.candidates[k].rejected.empty()) continue;
    if (best < 0 || det.candidates[k].cost < det.candidates[best].cost) best = static_cast<int>(k);
  }
  if (best < 0) {
    det.why_not = "no solid, free-standing plane of " + records::NumberText(nominal_w) + " x " +
                  records::NumberText(nominal_h) + " m facing the camera among " +
                  std::to_string(det.candidates.size()) + " planes in " +
                  std::to_string(clusters.size()) + " clusters";
    return det;
  }
  det.chosen = best;
  det.panel = found[best].fit.rect;
  det.evidence = found[best].fit.evidence;
  det.inlier_pixels = static_cast<int>(found[best].fit.on_plane_pixels.size());
  det.plane_rms_m = found[best].plane_rms_m;
  det.found = true;
  return det;
}

}  // namespace depthbias::panel
