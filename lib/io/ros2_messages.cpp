#include "io/ros2_messages.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "io/cdr.h"

namespace depthbias::io::ros2 {
namespace {

bool Done(const CdrReader& r, const char* what, std::string* why) {
  if (r.ok()) return true;
  *why = std::string(what) + ": " + r.why();
  return false;
}

// std_msgs/Header: builtin_interfaces/Time (int32 sec, uint32 nanosec), string frame_id.
void ReadHeader(CdrReader* r, std::int64_t* stamp_ns, std::string* frame_id) {
  const std::int64_t sec = r->I32();
  const std::int64_t nsec = r->U32();
  *stamp_ns = sec * 1000000000LL + nsec;
  *frame_id = r->String();
}

void SkipSequence(CdrReader* r, int kind) {  // 5 byte[], 6 bool[], 7 int64[], 8 double[], 9 str[]
  if (kind == 5 || kind == 6) {
    r->Bytes(r->Count(1));
  } else if (kind == 7) {
    for (std::uint32_t i = 0, n = r->Count(8); i < n && r->ok(); ++i) r->I64();
  } else if (kind == 8) {
    for (std::uint32_t i = 0, n = r->Count(8); i < n && r->ok(); ++i) r->F64();
  } else {
    for (std::uint32_t i = 0, n = r->Count(4); i < n && r->ok(); ++i) r->String();
  }
}

void ReadParameters(CdrReader* r, std::vector<Parameter>* out) {
  const std::uint32_t n = r->Count(16);
  for (std::uint32_t i = 0; i < n && r->ok(); ++i) {
    Parameter p;
    p.name = r->String();
    p.type = r->U8();  // ParameterValue
    p.bool_value = r->Bool();
    p.integer_value = r->I64();
    p.double_value = r->F64();
    p.string_value = r->String();
    for (int kind = 5; kind <= 9; ++kind) SkipSequence(r, kind);
    if (r->ok()) out->push_back(p);
  }
}

}  // namespace

bool DecodeImage(const std::uint8_t* data, std::size_t size, Image* out, std::string* why) {
  CdrReader r(data, size);
  ReadHeader(&r, &out->stamp_ns, &out->frame_id);
  out->height = r.U32();
  out->width = r.U32();
  out->encoding = r.String();
  out->is_bigendian = r.U8();
  out->step = r.U32();
  out->size = r.Count(1);
  out->data = r.Bytes(out->size);
  return Done(r, "sensor_msgs/msg/Image", why);
}

bool DecodeCameraInfo(const std::uint8_t* data, std::size_t size, CameraInfo* out,
                      std::string* why) {
  CdrReader r(data, size);
  ReadHeader(&r, &out->stamp_ns, &out->frame_id);
  out->height = r.U32();
  out->width = r.U32();
  out->distortion_model = r.String();
  const std::uint32_t nd = r.Count(8);
  out->d.clear();
  for (std::uint32_t i = 0; i < nd && r.ok(); ++i) out->d.push_back(r.F64());
  for (double& v : out->k) v = r.F64();
  for (double& v : out->r) v = r.F64();
  for (double& v : out->p) v = r.F64();
  return Done(r, "sensor_msgs/msg/CameraInfo", why);  // binning and roi are not needed
}

bool DecodeParameterEvent(const std::uint8_t* data, std::size_t size, std::string* node,
                          std::vector<Parameter>* out, std::string* why) {
  CdrReader r(data, size);
  r.I32();
  r.U32();  // stamp
  *node = r.String();
  ReadParameters(&r, out);  // new_parameters
  ReadParameters(&r, out);  // changed_parameters
  return Done(r, "rcl_interfaces/msg/ParameterEvent", why);
}

bool IsDepthEncoding(const std::string& e) {
  return e == "16UC1" || e == "mono16" || e == "32FC1";
}

bool ImageToDepthFrame(const Image& image, double depth_units_m, records::DepthFrame* out,
                       std::string* why) {
  const bool f32 = image.encoding == "32FC1";
  if (!IsDepthEncoding(image.encoding)) {
    *why = "depth image in encoding '" + image.encoding.substr(0, 32) +
           "' (16UC1, mono16 or 32FC1 expected)";
    return false;
  }
  const std::uint64_t bpp = f32 ? 4 : 2;
  const std::uint64_t w = image.width, h = image.height;
  if (w == 0 || h == 0 || w > camera::Intrinsics::kMaxImageSidePx ||
      h > camera::Intrinsics::kMaxImageSidePx) {
    *why = "depth image of " + std::to_string(w) + "x" + std::to_string(h) + " px";
    return false;
  }
  if (image.step < w * bpp || static_cast<std::uint64_t>(image.step) * h > image.size) {
    *why = "depth image of " + std::to_string(w) + "x" + std::to_string(h) + " px, step " +
           std::to_string(image.step) + ", holds only " + std::to_string(image.size) + " bytes";
    return false;
  }
  if (image.is_bigendian) {
    *why = "big-endian depth image";
    return false;
  }
  out->width = static_cast<int>(w);
  out->height = static_cast<int>(h);
  out->timestamp_ms = image.stamp_ns / 1e6;
  out->counts.resize(static_cast<std::size_t>(w * h));
  std::uint16_t* dst = out->counts.data();
  if (!f32) {
    out->depth_units_m = depth_units_m;
    for (std::uint64_t v = 0; v < h; ++v)
      std::memcpy(dst + v * w, image.data + v * image.step, static_cast<std::size_t>(w * 2));
    return true;
  }
  out->depth_units_m = kDepthUnitsM;
  for (std::uint64_t v = 0; v < h; ++v) {
    const std::uint8_t* row = image.data + v * image.step;
    for (std::uint64_t u = 0; u < w; ++u) {
      float z;
      std::memcpy(&z, row + 4 * u, 4);
      const double counts = std::round(static_cast<double>(z) / kDepthUnitsM);
      dst[v * w + u] = std::isfinite(z) && counts >= 1 && counts <= 65535
                           ? static_cast<std::uint16_t>(counts)
                           : 0;
    }
  }
  return true;
}

bool CameraInfoToIntrinsics(const CameraInfo& info, camera::Intrinsics* out, std::string* why) {
  camera::Intrinsics in;
  in.width = static_cast<int>(std::min<std::uint32_t>(info.width, 1u << 30));
  in.height = static_cast<int>(std::min<std::uint32_t>(info.height, 1u << 30));
  in.fx = info.k[0];
  in.fy = info.k[4];
  in.ppx = info.k[2];
  in.ppy = info.k[5];
  in.coeffs = {0, 0, 0, 0, 0};
  const std::string& model = info.distortion_model;
  const std::vector<double>& d = info.d;
  if (model == "plumb_bob" || model == "rational_polynomial") {
    in.model = camera::Distortion::kBrownConrady;
    for (std::size_t i = 0; i < 5 && i < d.size(); ++i) in.coeffs[i] = d[i];
    for (std::size_t i = 5; i < d.size(); ++i)
      if (d[i] != 0.0) {
        *why = "camera_info: " + model + " with k4..k6 not zero (no such model in depthbias)";
        return false;
      }
  } else if (model == "equidistant") {
    in.model = camera::Distortion::kKannalaBrandt4;
    for (std::size_t i = 0; i < 4 && i < d.size(); ++i) in.coeffs[i] = d[i];
  } else if (model.empty() || model == "none") {
    in.model = camera::Distortion::kNone;
  } else {
    *why = "camera_info: unknown distortion model '" + model.substr(0, 32) + "'";
    return false;
  }
  std::string bad;
  if (!in.IsValid(&bad)) {
    *why = "camera_info: " + bad;
    return false;
  }
  *out = in;
  return true;
}

}  // namespace depthbias::io::ros2
