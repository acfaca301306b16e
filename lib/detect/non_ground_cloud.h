#pragma once
// Private to detect. The voxels off the ground as a PCL cloud, for the clustering stages (ours
// and PCL's); it includes PCL, which stages.h keeps out of every other file.

#include <Eigen/Core>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <vector>

namespace depthbias::detect {

// rest: the voxel index of each point of the cloud, in the cloud's order.
inline pcl::PointCloud<pcl::PointXYZ>::Ptr NonGroundCloud(
    const std::vector<Eigen::Vector3f>& voxels, const std::vector<char>& is_ground,
    std::vector<int>* rest) {
  rest->clear();
  for (size_t i = 0; i < voxels.size(); ++i)
    if (!is_ground[i]) rest->push_back(static_cast<int>(i));
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->resize(rest->size());
  for (size_t j = 0; j < rest->size(); ++j) {
    const Eigen::Vector3f& q = voxels[static_cast<size_t>((*rest)[j])];
    (*cloud)[j] = pcl::PointXYZ(q.x(), q.y(), q.z());
  }
  return cloud;
}

}  // namespace depthbias::detect
