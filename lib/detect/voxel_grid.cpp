// Stage 2 (stages.h): the voxel grid.
#include <algorithm>
#include <cmath>

#include "common/hash.h"
#include "detect/stages.h"

namespace depthbias::detect {
namespace {

constexpr std::uint64_t kEmpty = ~0ULL;

using common::Mix64;

}  // namespace

void VoxelGrid::Build(const std::vector<Eigen::Vector3f>& points, float leaf_m,
                      std::vector<int>* voxel_of, std::vector<Eigen::Vector3f>* centroids) {
  size_t size = 1024;
  while (size < 2 * points.size()) size *= 2;
  if (keys_.size() != size) {
    keys_.assign(size, kEmpty);
    slots_.assign(size, -1);
  } else {
    std::fill(keys_.begin(), keys_.end(), kEmpty);
  }
  const std::uint64_t mask = size - 1;
  const float inv = 1.0f / leaf_m;
  voxel_of->resize(points.size());
  centroids->clear();
  counts_.clear();
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& p = points[i];
    // 21 bits per axis, offset so that ±1e6 cubes are positive.
    const auto cell = [inv](float v) {
      return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(v * inv)) +
                                        (1 << 20)) & 0x1FFFFF;
    };
    const std::uint64_t key = cell(p.x()) | cell(p.y()) << 21 | cell(p.z()) << 42;
    std::uint64_t h = Mix64(key) & mask;
    while (keys_[h] != kEmpty && keys_[h] != key) h = (h + 1) & mask;
    if (keys_[h] == kEmpty) {
      keys_[h] = key;
      slots_[h] = static_cast<int>(centroids->size());
      centroids->push_back(Eigen::Vector3f::Zero());
      counts_.push_back(0);
    }
    const int v = slots_[h];
    (*voxel_of)[i] = v;
    (*centroids)[static_cast<size_t>(v)] += p;
    ++counts_[static_cast<size_t>(v)];
  }
  for (size_t v = 0; v < centroids->size(); ++v)
    (*centroids)[v] /= static_cast<float>(counts_[v]);
}

}  // namespace depthbias::detect
