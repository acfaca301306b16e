// Stage 4 (stages.h): Euclidean clusters whose tolerance grows with range as σ_Z does.
#define PCL_NO_PRECOMPILE
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include "detect/non_ground_cloud.h"
#include "detect/stages.h"

namespace depthbias::detect {

std::vector<std::vector<int>> FindClusters(const std::vector<Eigen::Vector3f>& voxels,
                                           const std::vector<char>& is_ground,
                                           const ClusterParams& params, double noise_per_m2) {
  std::vector<std::vector<int>> clusters;
  std::vector<int> rest;  // voxel indices
  const pcl::PointCloud<pcl::PointXYZ>::Ptr cloud = NonGroundCloud(voxels, is_ground, &rest);
  if (rest.empty()) return clusters;
  pcl::search::KdTree<pcl::PointXYZ> tree(false);
  tree.setInputCloud(cloud);
  std::vector<char> seen(rest.size(), 0);
  pcl::Indices found;
  std::vector<float> dist2;
  std::vector<int> queue;
  for (size_t start = 0; start < rest.size(); ++start) {
    if (seen[start]) continue;
    seen[start] = 1;
    queue.assign(1, static_cast<int>(start));
    for (size_t head = 0; head < queue.size(); ++head) {
      const pcl::PointXYZ& q = (*cloud)[static_cast<size_t>(queue[head])];
      const double r2 = static_cast<double>(q.x) * q.x + static_cast<double>(q.y) * q.y +
                        static_cast<double>(q.z) * q.z;
      const double tol = params.base_tolerance_m + noise_per_m2 * r2;  // + k·σ_Z(r)
      tree.radiusSearch(q, tol, found, dist2);
      for (const auto j : found) {
        if (seen[static_cast<size_t>(j)]) continue;
        seen[static_cast<size_t>(j)] = 1;
        queue.push_back(j);
      }
    }
    if (static_cast<int>(queue.size()) < params.min_points) continue;
    std::vector<int> members;
    members.reserve(queue.size());
    for (int j : queue) members.push_back(rest[static_cast<size_t>(j)]);
    clusters.push_back(std::move(members));
  }
  return clusters;
}

}  // namespace depthbias::detect
