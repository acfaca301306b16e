// Agreement with librealsense: tests/data/camera_reference.csv holds pixels deprojected and
// points projected by pyrealsense2 2.56.5 itself (scripts/make_camera_reference.py).

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "camera/intrinsics.h"

namespace depthbias::camera {
namespace {

struct Row {
  std::map<std::string, std::string> text;
  double num(const std::string& key) const { return std::stod(text.at(key)); }
};

std::vector<Row> LoadReference() {
  const std::string path = std::string(DEPTHBIAS_TEST_DATA) + "/camera_reference.csv";
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << "cannot open " << path;
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  std::stringstream hs(line);
  for (std::string cell; std::getline(hs, cell, ',');) header.push_back(cell);
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    Row r;
    std::stringstream ls(line);
    size_t i = 0;
    for (std::string cell; std::getline(ls, cell, ',') && i < header.size(); ++i)
      r.text[header[i]] = cell;
    rows.push_back(r);
  }
  return rows;
}

Intrinsics FromRow(const Row& r) {
  Intrinsics in;
  in.width = static_cast<int>(r.num("width"));
  in.height = static_cast<int>(r.num("height"));
  in.fx = r.num("fx");
  in.fy = r.num("fy");
  in.ppx = r.num("ppx");
  in.ppy = r.num("ppy");
  const std::map<std::string, Distortion> models = {
      {"none", Distortion::kNone},
      {"brown_conrady", Distortion::kBrownConrady},
      {"inverse_brown_conrady", Distortion::kInverseBrownConrady},
      {"modified_brown_conrady", Distortion::kModifiedBrownConrady}};
  in.model = models.at(r.text.at("model"));
  in.coeffs = {r.num("k1"), r.num("k2"), r.num("p1"), r.num("p2"), r.num("k3")};
  return in;
}

TEST(CameraReference, MatchesLibrealsenseToOneInHundredThousandNormalized) {
  const std::vector<Row> rows = LoadReference();
  ASSERT_EQ(rows.size(), 1560u) << "reference table incomplete";
  std::map<std::string, double> worst;  // per camera/model/op, in normalized units
  for (const Row& r : rows) {
    const Intrinsics in = FromRow(r);
    const std::string key = r.text.at("camera") + "/" + r.text.at("model") + "/" + r.text.at("op");
    double err = 0.0;
    if (r.text.at("op") == "deproject") {
      const Eigen::Vector3d p = Deproject(in, {r.num("u"), r.num("v")}, r.num("depth_m"));
      const double z = r.num("z");
      err = std::max(std::abs(p.x() / p.z() - r.num("x") / z), std::abs(p.y() / p.z() - r.num("y") / z));
      EXPECT_NEAR(p.z(), z, 1e-6);
    } else {
      const Eigen::Vector2d px = Project(in, {r.num("x"), r.num("y"), r.num("z")});
      err = std::max(std::abs(px.x() - r.num("u")) / in.fx, std::abs(px.y() - r.num("v")) / in.fy);
    }
    worst[key] = std::max(worst[key], err);
    EXPECT_LT(err, 1e-5) << key << " at (" << r.text.at("u") << ", " << r.text.at("v") << ")";
  }
  EXPECT_EQ(worst.size(), 3u * 4u * 2u);
  for (const auto& [key, err] : worst) {
    std::ostringstream s;
    s << std::scientific << err;
    RecordProperty(key, s.str());
  }
}

}  // namespace
}  // namespace depthbias::camera
