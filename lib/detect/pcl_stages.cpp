// Stages 2 and 4 (stages.h) by PCL's own classes, beside the hand-written ones on the same
// inputs: pcl::VoxelGrid and pcl::ConditionalEuclideanClustering.
#include <algorithm>
#include <limits>

#define PCL_NO_PRECOMPILE
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/conditional_euclidean_clustering.h>

#include "detect/non_ground_cloud.h"
#include "detect/stages.h"

namespace depthbias::detect {

void PclVoxelGrid(const std::vector<Eigen::Vector3f>& points, float leaf_m,
                  std::vector<int>* voxel_of, std::vector<Eigen::Vector3f>* centroids) {
  voxel_of->assign(points.size(), -1);
  centroids->clear();
  if (points.empty()) return;
  pcl::PointCloud<pcl::PointXYZ>::Ptr in(new pcl::PointCloud<pcl::PointXYZ>);
  in->resize(points.size());
  for (size_t i = 0; i < points.size(); ++i)
    (*in)[i] = pcl::PointXYZ(points[i].x(), points[i].y(), points[i].z());
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(in);
  grid.setLeafSize(leaf_m, leaf_m, leaf_m);
  grid.setSaveLeafLayout(true);  // each point's voxel: getCentroidIndex
  pcl::PointCloud<pcl::PointXYZ> out;
  grid.filter(out);
  centroids->reserve(out.size());
  for (const auto& q : out) centroids->emplace_back(q.x, q.y, q.z);
  for (size_t i = 0; i < points.size(); ++i) (*voxel_of)[i] = grid.getCentroidIndex((*in)[i]);
}

std::vector<std::vector<int>> PclClusters(const std::vector<Eigen::Vector3f>& voxels,
                                          const std::vector<char>& is_ground,
                                          const ClusterParams& params, double noise_per_m2) {
  std::vector<std::vector<int>> clusters;
  std::vector<int> rest;  // voxel indices
  const pcl::PointCloud<pcl::PointXYZ>::Ptr cloud = NonGroundCloud(voxels, is_ground, &rest);
  if (rest.empty()) return clusters;
  double max_r2 = 0.0;
  for (const pcl::PointXYZ& q : *cloud)
    max_r2 = std::max(max_r2, static_cast<double>(q.getVector3fMap().squaredNorm()));
  pcl::ConditionalEuclideanClustering<pcl::PointXYZ> cec(false);
  cec.setInputCloud(cloud);
  // Every neighbour within the largest tolerance is offered to the condition, which keeps
  // those within the tolerance at the point being grown from: tol(r) = base + noise·r².
  cec.setClusterTolerance(static_cast<float>(params.base_tolerance_m + noise_per_m2 * max_r2));
  cec.setConditionFunction([&params, noise_per_m2](const pcl::PointXYZ& from,
                                                   const pcl::PointXYZ& to, float dist2) {
    const double r2 = static_cast<double>(from.x) * from.x +
                      static_cast<double>(from.y) * from.y +
                      static_cast<double>(from.z) * from.z;
    const double tol = params.base_tolerance_m + noise_per_m2 * r2;
    (void)to;
    return static_cast<double>(dist2) <= tol * tol;
  });
  cec.setMinClusterSize(params.min_points);
  cec.setMaxClusterSize(std::numeric_limits<int>::max());
  pcl::IndicesClusters found;
  cec.segment(found);
  clusters.reserve(found.size());
  for (const auto& c : found) {
    std::vector<int> members;
    members.reserve(c.indices.size());
    for (const auto j : c.indices) members.push_back(rest[static_cast<size_t>(j)]);
    clusters.push_back(std::move(members));
  }
  return clusters;
}

}  // namespace depthbias::detect
