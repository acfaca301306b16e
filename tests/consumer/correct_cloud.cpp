// A program of another project, built against the installed depthbias (find_package): reads the
// first depth frame of a RealSense recording with depthbias::io, makes it a
// pcl::PointCloud<pcl::PointXYZ>, corrects every point with a fitted bias model
// (model::BiasModel from a weights YAML) and prints the corrected range of one pixel's point.
//   correct_cloud BAG WEIGHTS.yaml LIGHT [U V]     (default pixel: the image centre)
// The scenario is (LIGHT, the bag's recorded Visual_Preset, its Emitter_Enabled).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include <Eigen/Core>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <depthbias/camera/intrinsics.h>
#include <depthbias/camera/presets.h>
#include <depthbias/io/bag.h>
#include <depthbias/io/weights_yaml.h>
#include <depthbias/model/bias_model.h>

int main(int argc, char** argv) {
  using namespace depthbias;
  if (argc != 4 && argc != 6) {
    std::fprintf(stderr, "usage: correct_cloud BAG WEIGHTS.yaml LIGHT [U V]\n");
    return 2;
  }
  try {
    io::BagReader reader(argv[1]);
    const io::BagInfo& info = reader.info();
    records::DepthFrame frame;
    if (!reader.Next(&frame)) throw std::runtime_error(std::string(argv[1]) + ": no depth frame");
    const auto preset_option = info.options.find("Visual_Preset");
    const auto emitter_option = info.options.find("Emitter_Enabled");
    const std::string preset = preset_option == info.options.end()
                                   ? "*" : camera::PresetName(preset_option->second);
    const std::string emitter =
        emitter_option == info.options.end() ? "*" : (emitter_option->second > 0 ? "on" : "off");
    const int u = argc == 6 ? std::atoi(argv[4]) : frame.width / 2;
    const int v = argc == 6 ? std::atoi(argv[5]) : frame.height / 2;
    if (u < 0 || v < 0 || u >= frame.width || v >= frame.height || frame.at(u, v) == 0) {
      throw std::runtime_error("pixel (" + std::to_string(u) + ", " + std::to_string(v) +
                               ") is outside the image or has no depth");
    }

    // The organized cloud of the frame (NaN where there is no depth), as a PCL user holds it.
    pcl::PointCloud<pcl::PointXYZ> cloud(frame.width, frame.height);
    for (int y = 0; y < frame.height; ++y) {
      for (int x = 0; x < frame.width; ++x) {
        const double depth_m = frame.DepthAt(x, y);
        const float nan = std::nanf("");
        pcl::PointXYZ& p = cloud.at(x, y);
        if (depth_m <= 0) {
          p = pcl::PointXYZ(nan, nan, nan);
          continue;
        }
        const Eigen::Vector3d q =
            camera::Deproject(info.depth_intrinsics, Eigen::Vector2d(x, y), depth_m);
        p = pcl::PointXYZ(q.x(), q.y(), q.z());
      }
    }
    const pcl::PointXYZ raw = cloud.at(u, v);

    // Every valid point moved along its ray to its corrected range.
    const model::BiasModel bias_model(io::ReadWeightsYaml(argv[2]));
    const model::ScenarioModel& scenario = bias_model.Scenario(argv[3], preset, emitter);
    int corrected = 0, failed = 0;
    for (pcl::PointXYZ& p : cloud.points) {
      if (!std::isfinite(p.z)) continue;
      Eigen::Vector3d q(p.x, p.y, p.z);
      if (scenario.CorrectPoint(&q)) {
        p = pcl::PointXYZ(q.x(), q.y(), q.z());
        ++corrected;
      } else {
        ++failed;
      }
    }

    const pcl::PointXYZ& out = cloud.at(u, v);
    const double depth_m = raw.z;
    const double range_m = raw.getVector3fMap().cast<double>().norm();
    const double angle_deg =
        std::atan2(std::hypot(double{raw.x}, double{raw.y}), double{raw.z}) * 180.0 / M_PI;
    std::printf("scenario light=%s preset=%s emitter=%s model=%s\n", argv[3], preset.c_str(),
                emitter.c_str(), bias_model.weights().model.c_str());
    std::printf("cloud %ux%u corrected=%d failed=%d\n", cloud.width, cloud.height, corrected,
                failed);
    std::printf("pixel %d %d depth_m=%.9g angle_deg=%.9g range_m=%.9g corrected_range_m=%.9g\n",
                u, v, depth_m, angle_deg, range_m, out.getVector3fMap().cast<double>().norm());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "correct_cloud: %s\n", e.what());
    return 1;
  }
}
