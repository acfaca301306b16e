// Stage 3 (stages.h): the ground, a RANSAC plane whose normal is within max_tilt_deg of the
// camera's up axis, refined by least squares on its band.
#include <cmath>
#include <memory>
#include <numeric>

#include <Eigen/Eigenvalues>

// PCL's templates are instantiated here from its headers (as in lib/panel), so that only
// libpcl_common is linked and start-up stays short.
#define PCL_NO_PRECOMPILE
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/ransac.h>
#include <pcl/sample_consensus/sac_model_perpendicular_plane.h>

#include "common/seeded_ransac.h"
#include "detect/stages.h"

namespace depthbias::detect {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

// Total least squares plane n·p + d = 0 of points (PCA), or false when degenerate.
bool FitPlane(const std::vector<Eigen::Vector3d>& pts, Eigen::Vector3d* n, double* d) {
  if (pts.size() < 3) return false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) cov += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  if (eig.info() != Eigen::Success) return false;
  *n = eig.eigenvectors().col(0);
  *d = -n->dot(mean);
  return true;
}

}  // namespace

Ground FindGround(const std::vector<Eigen::Vector3f>& voxels, const GroundParams& params) {
  Ground g;
  const int nv = static_cast<int>(voxels.size());
  g.is_ground.assign(voxels.size(), 0);
  if (!params.enabled || nv < 3) return g;
  Cloud::Ptr cloud(new Cloud);
  cloud->resize(voxels.size());
  for (size_t i = 0; i < voxels.size(); ++i)
    (*cloud)[i] = pcl::PointXYZ(voxels[i].x(), voxels[i].y(), voxels[i].z());
  pcl::Indices all(voxels.size());
  std::iota(all.begin(), all.end(), 0);
  auto sac = std::make_shared<
      common::Seeded<pcl::SampleConsensusModelPerpendicularPlane<pcl::PointXYZ>>>(cloud, all,
                                                                                  params.seed);
  sac->setAxis(Eigen::Vector3f(0, 1, 0));
  sac->setEpsAngle(params.max_tilt_deg * kDegToRad);
  common::CountingRansac ransac(sac, params.distance_m);
  ransac.setMaxIterations(params.max_iterations);
  ransac.setProbability(params.probability);
  if (!ransac.computeModel()) return g;
  g.iterations = ransac.iterations();
  pcl::Indices inliers;
  ransac.getInliers(inliers);
  Eigen::VectorXf coeff;
  ransac.getModelCoefficients(coeff);
  Eigen::Vector3d n(coeff.size() == 4 ? coeff[0] : 0, coeff.size() == 4 ? coeff[1] : 0,
                    coeff.size() == 4 ? coeff[2] : 0);
  double d = coeff.size() == 4 ? coeff[3] : 0.0;
  const double len = n.norm();
  if (!(len > 0) || inliers.size() < params.min_fraction * nv) return g;
  n /= len;
  d /= len;
  // Least-squares refinement on the points within the band.
  for (int it = 0; it < params.refine_iterations; ++it) {
    std::vector<Eigen::Vector3d> band;
    for (int i = 0; i < nv; ++i) {
      const Eigen::Vector3d q = voxels[static_cast<size_t>(i)].cast<double>();
      if (std::fabs(n.dot(q) + d) < params.distance_m) band.push_back(q);
    }
    Eigen::Vector3d n2;
    double d2;
    if (!FitPlane(band, &n2, &d2)) break;
    if (n2.dot(n) < 0) {
      n2 = -n2;
      d2 = -d2;
    }
    n = n2;
    d = d2;
  }
  if (d < 0) {  // the camera on the + side
    n = -n;
    d = -d;
  }
  g.found = true;
  g.normal = n;
  g.d = d;
  for (int i = 0; i < nv; ++i) {
    // The ground and whatever lies below it.
    if (n.dot(voxels[static_cast<size_t>(i)].cast<double>()) + d < params.distance_m) {
      g.is_ground[static_cast<size_t>(i)] = 1;
      ++g.inliers;
    }
  }
  return g;
}

}  // namespace depthbias::detect
