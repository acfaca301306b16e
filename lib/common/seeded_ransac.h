// Private to common. Not installed: it includes PCL. lib/panel and lib/detect include it from
// their .cpp files, which compile PCL's sample-consensus templates themselves (PCL_NO_PRECOMPILE
// before this header, PCL's include directories on their targets).
//
// PCL's sample-consensus models seed their sampler with a fixed 12345, and its RANSAC does not
// say how many iterations it ran; these two add both.
#pragma once

#include <cstdint>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/ransac.h>

namespace depthbias::common {

// A sample-consensus model (e.g. pcl::SampleConsensusModelPlane<pcl::PointXYZ>) whose sampler
// is seeded with the caller's seed.
template <class Model>
class Seeded : public Model {
 public:
  Seeded(const typename pcl::PointCloud<pcl::PointXYZ>::ConstPtr& cloud,
         const pcl::Indices& indices, std::uint64_t seed)
      : Model(cloud, indices) {
    this->rng_alg_.seed(static_cast<unsigned>(seed ^ (seed >> 32)));
  }
};

// RANSAC that reports how many iterations it ran.
class CountingRansac : public pcl::RandomSampleConsensus<pcl::PointXYZ> {
 public:
  using pcl::RandomSampleConsensus<pcl::PointXYZ>::RandomSampleConsensus;
  int iterations() const { return iterations_; }
};

}  // namespace depthbias::common
