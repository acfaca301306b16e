// Each stage of the detector alone (lib/detect/stages.h), on inputs whose answer is known: the
// samples a frame gives, the voxel grid against a brute-force one, the ground of a tilted plane
// and none of a wall, clusters kept apart or joined by the tolerance, an obstacle's measures,
// and the margin as the model gives it.
#include "detect/stages.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include "scene_fixture.h"

namespace depthbias::detect {
namespace {

camera::Intrinsics SmallCamera() {
  camera::Intrinsics in;
  in.width = 64;
  in.height = 48;
  in.fx = in.fy = 40.0;
  in.ppx = 32.0;
  in.ppy = 24.0;
  in.model = camera::Distortion::kNone;
  in.coeffs = {0, 0, 0, 0, 0};
  return in;
}

TEST(Stages, CloudKeepsValidSamplesOnly) {
  const camera::Intrinsics in = SmallCamera();
  const SampleRays rays = MakeSampleRays(in, 4);
  ASSERT_EQ(rays.pixel.size(), 16u * 12u);
  records::DepthFrame f;
  f.width = in.width;
  f.height = in.height;
  f.counts.assign(static_cast<size_t>(in.width) * in.height, 0);
  // Five samples: no depth, full scale, 0.3 m (too near), 25 m (too far), 5 m.
  const std::uint16_t counts[] = {0, 0xFFFF, 300, 25000, 5000};
  for (int k = 0; k < 5; ++k) f.counts[rays.pixel[static_cast<size_t>(k)]] = counts[k];
  SampledCloud cloud;
  BuildCloud(f, rays, CloudParams{}, &cloud);
  ASSERT_EQ(cloud.points.size(), 1u);
  EXPECT_EQ(cloud.sample_of[0], 4);
  EXPECT_FLOAT_EQ(cloud.depth_m[4], 5.0f);
  EXPECT_EQ(cloud.depth_m[3], 0.0f);
  EXPECT_TRUE(cloud.points[0].isApprox(5.0f * rays.ray[4]));
  EXPECT_DOUBLE_EQ(cloud.valid_pct, 100.0 / 192.0);
  EXPECT_TRUE(IsBlind(cloud, CloudParams{}));
  CloudParams lenient;
  lenient.min_valid_pct = 0.5;
  EXPECT_FALSE(IsBlind(cloud, lenient));
}

TEST(Stages, VoxelGridMatchesABruteForceGrid) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  std::vector<Eigen::Vector3f> points(5000);
  for (auto& p : points) p = {u(rng), u(rng), 5.0f + u(rng)};
  std::vector<int> voxel_of;
  std::vector<Eigen::Vector3f> centroids;
  VoxelGrid grid;
  grid.Build(points, 0.5f, &voxel_of, &centroids);
  struct Sum {
    Eigen::Vector3d points = Eigen::Vector3d::Zero();
    int n = 0;
  };
  std::map<std::tuple<int, int, int>, Sum> brute;
  for (const auto& p : points) {
    auto& cell = brute[{static_cast<int>(std::floor(p.x() * 2.0f)),
                        static_cast<int>(std::floor(p.y() * 2.0f)),
                        static_cast<int>(std::floor(p.z() * 2.0f))}];
    cell.points += p.cast<double>();
    ++cell.n;
  }
  ASSERT_EQ(centroids.size(), brute.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const auto& cell = brute[{static_cast<int>(std::floor(points[i].x() * 2.0f)),
                              static_cast<int>(std::floor(points[i].y() * 2.0f)),
                              static_cast<int>(std::floor(points[i].z() * 2.0f))}];
    const Eigen::Vector3d mean = cell.points / cell.n;
    EXPECT_LT((centroids[static_cast<size_t>(voxel_of[i])].cast<double>() - mean).norm(), 1e-5);
  }
  // Built again (the table kept), the same answer.
  std::vector<int> again_of;
  std::vector<Eigen::Vector3f> again;
  grid.Build(points, 0.5f, &again_of, &again);
  EXPECT_EQ(again_of, voxel_of);
}

// A ground 1.2 m below the camera pitched by 5°, a box standing on it; a wall alone.
TEST(Stages, GroundOfATiltedPlaneAndNoneOfAWall) {
  const double pitch = 5.0 * M_PI / 180.0;
  const Eigen::Vector3d up(0.0, -std::cos(pitch), std::sin(pitch));  // ground normal, camera frame
  std::vector<Eigen::Vector3f> voxels;
  for (double x = -3; x <= 3; x += 0.1)
    for (double z = 2; z <= 12; z += 0.1) {
      // A point on the plane up·p + 1.2 = 0 over (x, z).
      const double y = (1.2 + up.z() * z) / -up.y();
      voxels.emplace_back(x, y, z);
    }
  const size_t ground_count = voxels.size();
  for (double h = 0.3; h <= 1.7; h += 0.1)
    for (double x = 0; x <= 0.5; x += 0.1) {
      const Eigen::Vector3d foot(x, (1.2 + up.z() * 6.0) / -up.y(), 6.0);
      voxels.push_back((foot + h * up).cast<float>());
    }
  const Ground g = FindGround(voxels, GroundParams{});
  ASSERT_TRUE(g.found);
  EXPECT_LT((g.normal - up).norm(), 1e-3);
  EXPECT_NEAR(g.d, 1.2, 1e-3);
  EXPECT_EQ(g.inliers, static_cast<int>(ground_count));
  for (size_t i = ground_count; i < voxels.size(); ++i) EXPECT_EQ(g.is_ground[i], 0);
  std::vector<Eigen::Vector3f> wall;
  for (double x = -3; x <= 3; x += 0.1)
    for (double y = -1; y <= 1; y += 0.1) wall.emplace_back(x, y, 5.0);
  EXPECT_FALSE(FindGround(wall, GroundParams{}).found);
  GroundParams off;
  off.enabled = false;
  EXPECT_FALSE(FindGround(voxels, off).found);
}

// Two blobs 1 m apart at 5 m; a speck of 3 voxels; ground voxels left out.
TEST(Stages, ClustersApartOrJoinedByTheTolerance) {
  std::vector<Eigen::Vector3f> voxels;
  std::vector<char> ground;
  const auto blob = [&](float x0, int n, char is_ground) {
    for (int i = 0; i < n; ++i) {
      voxels.emplace_back(x0 + 0.1f * (i % 4), 0.1f * (i / 4), 5.0f);
      ground.push_back(is_ground);
    }
  };
  blob(-1.3f, 20, 0);  // x in [-1.3, -1.0]
  blob(0.0f, 20, 0);   // 1 m from it
  blob(3.0f, 3, 0);    // a speck
  blob(6.0f, 20, 1);   // ground
  const ClusterParams p;  // 0.2 m, at least 6 voxels
  const auto apart = FindClusters(voxels, ground, p, 0.0);
  ASSERT_EQ(apart.size(), 2u);
  EXPECT_EQ(apart[0].size(), 20u);
  EXPECT_EQ(apart[1].size(), 20u);
  for (int v : apart[1]) EXPECT_GE(v, 20);
  // At 5 m a tolerance of 0.2 + 0.04·25 = 1.2 m joins them.
  const auto joined = FindClusters(voxels, ground, p, 0.04);
  ASSERT_EQ(joined.size(), 1u);
  EXPECT_EQ(joined[0].size(), 40u);
}

// PCL's classes on the same inputs: pcl::VoxelGrid gives the same voxels (in its own order),
// pcl::ConditionalEuclideanClustering with tol(r) as its condition the same clusters, on a
// rendered frame of people, bushes and ground.
TEST(Stages, PclVoxelGridAndConditionalClusteringGiveTheSameAnswer) {
  const auto p = testing::Scene({testing::Person(4, -20), testing::Person(13, -21),
                                 testing::Bush(13, -15.5), testing::Person(15, 10)});
  const SampleRays rays = MakeSampleRays(p.sensor.intrinsics, 4);
  SampledCloud cloud;
  BuildCloud(testing::Render(p, 1)[0], rays, CloudParams{}, &cloud);
  std::vector<int> own_of, pcl_of;
  std::vector<Eigen::Vector3f> own, pcl;
  VoxelGrid grid;
  grid.Build(cloud.points, 0.1f, &own_of, &own);
  PclVoxelGrid(cloud.points, 0.1f, &pcl_of, &pcl);
  ASSERT_EQ(own.size(), pcl.size());
  ASSERT_GT(own.size(), 1000u);
  for (size_t i = 0; i < cloud.points.size(); ++i) {
    EXPECT_LT((own[static_cast<size_t>(own_of[i])] - pcl[static_cast<size_t>(pcl_of[i])]).norm(),
              1e-4f);
  }
  const Ground ground = FindGround(own, GroundParams{});
  ASSERT_TRUE(ground.found);
  const double noise_per_m2 = 0.08 / (640.0 * 0.095);
  auto a = FindClusters(own, ground.is_ground, ClusterParams{}, noise_per_m2);
  auto b = PclClusters(own, ground.is_ground, ClusterParams{}, noise_per_m2);
  ASSERT_GE(a.size(), 3u);
  for (auto* clusters : {&a, &b})
    for (auto& c : *clusters) std::sort(c.begin(), c.end());
  EXPECT_EQ(a, b);
}

TEST(Stages, ObstacleMeasuredOnItsOwnPoints) {
  // A 0.5 m wide, 1.5 m tall front at Z = 8 m, 1 m right; ground 1 m below the camera.
  std::vector<Eigen::Vector3f> points;
  std::vector<int> members;
  for (int i = 0; i <= 5; ++i)
    for (int j = 0; j <= 15; ++j) {
      members.push_back(static_cast<int>(points.size()));
      points.emplace_back(0.75f + 0.1f * i, 1.0f - 0.1f * j, 8.0f);
    }
  Ground g;
  g.found = true;
  g.normal = {0.0, -1.0, 0.0};
  g.d = 1.0;
  DetectedObstacle o;
  ASSERT_TRUE(MeasureObstacle(points, members, g, ObstacleParams{}, &o));
  EXPECT_EQ(o.points, 96);
  EXPECT_NEAR(o.height_m, 1.5, 1e-5);
  EXPECT_NEAR(o.depth_m, 8.0, 1e-5);
  EXPECT_NEAR(o.centroid_m.x(), 1.0, 1e-5);
  EXPECT_NEAR(o.azimuth_deg, std::atan2(1.0, 8.0) * 180.0 / M_PI, 1e-4);
  EXPECT_GT(o.range_m, 8.0);
  EXPECT_LT(o.range_m, std::hypot(1.25, 1.0, 8.0));
  ObstacleParams tall;
  tall.min_height_m = 1.6;
  EXPECT_FALSE(MeasureObstacle(points, members, g, tall, &o));
}

TEST(Stages, MarginIsTheModelsAndNeverBeyondTheRawRange) {
  const double delta_px = 0.25;  // the model moves readings farther
  const model::BiasModel bias(testing::Weights(delta_px, 1.0, 0.005, 1e-5));
  const model::ScenarioModel& s = bias.Scenario("daylight", "HD");
  DetectedObstacle o;
  o.depth_m = 10.0;
  o.off_axis_deg = 5.0;
  o.range_m = 10.04;
  o.points = 100;
  DetectorParams p;
  ApplyMargin(s, p, 0.15, 60.8, &o);
  EXPECT_DOUBLE_EQ(o.corrected_range_m, s.CorrectedM(10.0, 5.0));
  const double reading = 1.2533 * 100.0 * 0.15 / 60.8 / 10.0;
  EXPECT_DOUBLE_EQ(o.std_m, std::hypot(s.PredictiveStdM(10.0, 5.0), reading));
  ASSERT_GT(o.corrected_range_m - 2.0 * o.std_m, o.range_m);
  EXPECT_EQ(o.safe_range_m, o.range_m);
  EXPECT_EQ(o.zone, ZoneFor(o.range_m, p.zones));
  p.safe_beyond_raw = true;
  ApplyMargin(s, p, 0.15, 60.8, &o);
  EXPECT_DOUBLE_EQ(o.safe_range_m, o.corrected_range_m - 2.0 * o.std_m);
}

}  // namespace
}  // namespace depthbias::detect
