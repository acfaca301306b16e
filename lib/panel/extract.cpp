#include "panel/extract.h"
#include "panel/pcl_quiet.h"

#include "panel/panel_fit.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <utility>

namespace depthbias::panel {
namespace {

bool FrameMatches(const records::DepthFrame& f, const camera::Intrinsics& in, std::string* why) {
  if (f.width != in.width || f.height != in.height ||
      f.counts.size() != static_cast<std::size_t>(in.width) * in.height) {
    *why = "frame " + std::to_string(f.frame_number) + " is " + std::to_string(f.width) + "x" +
           std::to_string(f.height) + ", the intrinsics say " + std::to_string(in.width) + "x" +
           std::to_string(in.height);
    return false;
  }
  if (!(f.depth_units_m > 0) || !std::isfinite(f.depth_units_m)) {
    *why = "frame " + std::to_string(f.frame_number) + " has no valid depth units";
    return false;
  }
  return true;
}

// Adds every remaining frame of source to measurer; false (why set) at a frame that does not
// match the intrinsics.
bool MeasureAll(FrameSource& source, const camera::Intrinsics& intrinsics,
                records::DepthFrame* frame, metrics::RegionMetrics* kernel,
                std::uint64_t* frames_read, std::string* why) {
  while (source.Next(frame)) {
    ++*frames_read;
    if (!FrameMatches(*frame, intrinsics, why)) return false;
    kernel->AddFrame(*frame);
  }
  return true;
}

metrics::KernelParams KernelParamsOf(const PanelParams& p) {
  metrics::KernelParams k;
  k.baseline_m = p.baseline_m;
  k.region_margin_px = p.region_margin_px;
  return k;
}

ExtractResult Fail(ExtractResult* r, const std::string& status, const std::string& message) {
  r->metrics.status = status;
  r->metrics.message = message;
  return std::move(*r);
}

}  // namespace

ExtractResult ExtractPanel(FrameSource& source, const camera::Intrinsics& intrinsics,
                           const PanelParams& params, const SearchWindow& window,
                           const std::optional<PixelBox>& box) {
  QuietPcl();
  ExtractResult res;
  std::string why;
  if (!params.IsValid(&why)) {
    return Fail(&res, "error", "bad parameters: " + why);
  }
  if (!intrinsics.IsValid(&why)) {
    return Fail(&res, "error", "bad intrinsics: " + why);
  }
  if (intrinsics.model == camera::Distortion::kModifiedBrownConrady) {
    return Fail(&res, "error",
                "depth stream has Modified Brown-Conrady distortion, which cannot be deprojected");
  }
  const metrics::RayTable rays(intrinsics);
  records::DepthFrame frame;

  // Box mode: the region is given, one pass measures it.
  if (box) {
    res.passes = 1;
    res.region = metrics::RegionFromBox(intrinsics.width, intrinsics.height, box->u0, box->v0, box->u1,
                               box->v1);
    if (res.region.pixels.empty()) {
      return Fail(&res, "error", "the box lies outside the image");
    }
    metrics::KernelParams kp = KernelParamsOf(params);
    kp.region_margin_px = 0;  // the box's pixels are the region, no margin to add back
    metrics::RegionMetrics kernel(intrinsics, res.region, kp);
    if (!MeasureAll(source, intrinsics, &frame, &kernel, &res.frames_read, &why))
      return Fail(&res, "error", why);
    res.measure = kernel.Finish({0, -1, 0}, &res.metrics);
    if (!res.measure.success) return Fail(&res, "no_panel", res.measure.message);
    return res;
  }

  // Automatic mode: pool the first detection_frames frames (every frame for 0) and find the
  // panel. With keep_detection_frames (and a bounded detection_frames) the pooled frames are
  // kept, measured, and the recording read on from where pooling stopped: every frame is read
  // and decompressed once, and memory is bounded by detection_frames, not by the recording's
  // length. Otherwise the recording is read again from the start to measure.
  const std::uint64_t limit = static_cast<std::uint64_t>(params.detection_frames);
  const bool keep = params.keep_detection_frames && limit > 0;
  std::vector<records::DepthFrame> pooled;
  DepthAccumulator acc(intrinsics.width, intrinsics.height);
  res.passes = 1;
  while (limit == 0 || acc.frames() < limit) {
    if (!source.Next(&frame)) break;
    ++res.frames_read;
    if (!FrameMatches(frame, intrinsics, &why)) return Fail(&res, "error", why);
    acc.Add(frame);
    if (keep) {
      pooled.push_back(std::move(frame));
      frame = records::DepthFrame();
    }
  }
  if (acc.frames() == 0) return Fail(&res, "error", "the recording holds no depth frame");
  res.detection = DetectPanel(rays, acc, params, window);
  if (!res.detection.found) return Fail(&res, "no_panel", res.detection.why_not);
  res.region =
      metrics::RegionFromRectangle(intrinsics, res.detection.panel, params.region_margin_px);
  if (res.region.pixels.empty())
    return Fail(&res, "no_panel", "the panel's image region is empty after the margin");
  // A pixel counts as the panel's only where the panel covers it: pixels of the rectangle in
  // which the pooled frames show the background, the ground or an occluder are left out, by the
  // decision the simulator's metrics-only path makes too (metrics/panel_pixels.h).
  {
    metrics::PanelPixels decided = DecideRegionPixels(
        acc, intrinsics, res.region,
        res.detection.ground_found ? &res.detection.ground : nullptr, params);
    res.excluded_pixels = decided.excluded();
    res.region.pixels.swap(decided.pixels);
  }
  if (res.region.pixels.empty())
    return Fail(&res, "no_panel", "no pixel of the panel's region shows the panel");

  // Measure the region over every frame.
  metrics::RegionMetrics kernel(intrinsics, res.region, KernelParamsOf(params));
  if (keep) {
    for (const records::DepthFrame& f : pooled) kernel.AddFrame(f);
    pooled.clear();
    pooled.shrink_to_fit();
  } else {
    if (!source.Rewind())
      return Fail(&res, "error", "cannot read the recording a second time to measure the panel");
    res.passes = 2;
  }
  if (!MeasureAll(source, intrinsics, &frame, &kernel, &res.frames_read, &why))
    return Fail(&res, "error", why);
  const Eigen::Vector3d up = res.detection.panel.axis_up;
  res.measure = kernel.Finish(up, &res.metrics);
  if (!res.measure.success) return Fail(&res, "no_panel", res.measure.message);
  return res;
}

namespace {

std::string Num(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream s;
  s << std::setprecision(9) << v;
  return s.str();
}

std::string EvidenceJson(const WindowEvidence& e) {
  std::ostringstream j;
  j << "\"evidence\": {\"on_plane\": " << e.on_plane << ", \"behind\": " << e.behind
    << ", \"ground\": " << e.ground << ", \"in_front\": " << e.in_front
    << ", \"ring_on_plane\": " << e.ring_on_plane << ", \"ring_observed\": " << e.ring_observed
    << ", \"occupied_sides\": " << e.occupied_sides
    << ", \"covered_width_m\": " << Num(e.covered_width_m)
    << ", \"covered_height_m\": " << Num(e.covered_height_m)
    << ", \"cut_off\": {\"pixels\": " << e.cut_off_px << ", \"below_m\": " << Num(e.cut_off_below_m)
    << ", \"above_m\": " << Num(e.cut_off_above_m) << ", \"left_m\": " << Num(e.cut_off_left_m)
    << ", \"right_m\": " << Num(e.cut_off_right_m) << "}}";
  return j.str();
}

std::string Vec(const Eigen::Vector3d& v) {
  return "[" + Num(v.x()) + ", " + Num(v.y()) + ", " + Num(v.z()) + "]";
}

std::string Quote(const std::string& text) {
  std::string out = "\"";
  for (char ch : text) {
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (static_cast<unsigned char>(ch) < 0x20) {
      out += ' ';
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

}  // namespace

std::string DetectionJson(const ExtractResult& r, const camera::Intrinsics& in,
                          const std::string& extra_members) {
  std::ostringstream j;
  const PanelDetection& d = r.detection;
  j << "{";
  if (!extra_members.empty()) j << extra_members << ", ";
  j << "\"status\": " << Quote(r.metrics.status) << ", \"message\": " << Quote(r.metrics.message);
  j << ", \"intrinsics\": {\"width\": " << in.width << ", \"height\": " << in.height
    << ", \"fx\": " << Num(in.fx) << ", \"fy\": " << Num(in.fy) << ", \"ppx\": " << Num(in.ppx)
    << ", \"ppy\": " << Num(in.ppy) << ", \"model\": " << Quote(camera::DistortionName(in.model))
    << ", \"coeffs\": [" << Num(in.coeffs[0]) << ", " << Num(in.coeffs[1]) << ", "
    << Num(in.coeffs[2]) << ", " << Num(in.coeffs[3]) << ", " << Num(in.coeffs[4]) << "]}";
  j << ", \"frames_read\": " << r.frames_read << ", \"passes\": " << r.passes
    << ", \"frames_detection\": " << d.frames << ", \"frames_measured\": " << r.measure.frames
    << ", \"frames_with_depth\": " << r.measure.frames_with_depth;
  if (d.found) {
    const metrics::PanelRectangle& p = d.panel;
    j << ", \"plane\": {\"normal\": " << Vec(p.plane.normal)
      << ", \"offset_m\": " << Num(p.plane.offset_m) << ", \"rms_m\": " << Num(d.plane_rms_m)
      << "}, \"center_m\": " << Vec(p.center_m) << ", \"width_m\": " << Num(p.width_m)
      << ", \"height_m\": " << Num(p.height_m) << ", \"corners_m\": [";
    const auto corners = p.Corners();
    for (int k = 0; k < 4; ++k) j << (k ? ", " : "") << Vec(corners[k]);
    j << "]";
  }
  if (r.measure.plane.ok) {
    j << ", \"measured_plane\": {\"normal\": " << Vec(r.measure.plane.plane.normal)
      << ", \"offset_m\": " << Num(r.measure.plane.plane.offset_m)
      << ", \"rms_m\": " << Num(r.measure.plane.rms_m) << "}";
  }
  j << ", \"outline_px\": [";
  for (std::size_t k = 0; k < r.region.outline_px.size(); ++k)
    j << (k ? ", " : "") << "[" << Num(r.region.outline_px[k].x()) << ", "
      << Num(r.region.outline_px[k].y()) << "]";
  j << "], \"region_px\": " << r.region.size() << ", \"region_runs\": [";
  // The region as [v, u_begin, u_end) runs of pixels, row by row.
  const std::vector<std::uint32_t>& px = r.region.pixels;
  for (std::size_t k = 0; k < px.size();) {
    std::size_t e = k + 1;
    while (e < px.size() && px[e] == px[e - 1] + 1 && px[e] % r.region.width != 0) ++e;
    const int width = r.region.width;
    j << (k ? ", " : "") << "[" << px[k] / width << ", " << px[k] % width << ", "
      << px[e - 1] % width + 1 << "]";
    k = e;
  }
  j << "]";
  if (!r.region.pixels.empty())
    j << ", \"region_bbox\": [" << r.region.u_min << ", " << r.region.v_min << ", "
      << r.region.u_max + 1 << ", " << r.region.v_max + 1 << "]";
  if (d.found) j << ", " << EvidenceJson(d.evidence);
  j << ", \"excluded_pixels\": " << r.excluded_pixels;
  j << ", \"inlier_pixels\": " << d.inlier_pixels << ", \"cloud_points\": " << d.cloud_points
    << ", \"ground_found\": " << (d.ground_found ? "true" : "false")
    << ", \"ground_inliers\": " << d.ground_inliers;
  if (d.ground_found)
    j << ", \"ground_plane\": {\"normal\": " << Vec(d.ground.normal)
      << ", \"offset_m\": " << Num(d.ground.offset_m) << "}";
  j << ", \"clusters\": " << d.clusters << ", \"ransac_iterations\": " << d.ransac_iterations
    << ", \"candidates\": [";
  for (std::size_t k = 0; k < d.candidates.size(); ++k) {
    const PanelCandidate& c = d.candidates[k];
    j << (k ? ", " : "") << "{\"cluster\": " << c.cluster << ", \"inliers\": " << c.inliers
      << ", \"width_m\": " << Num(c.width_m) << ", \"height_m\": " << Num(c.height_m)
      << ", \"range_m\": " << Num(c.range_m) << ", \"off_axis_deg\": " << Num(c.off_axis_deg)
      << ", \"see_through\": " << Num(c.see_through)
      << ", \"ring_share\": " << Num(c.ring_share) << ", " << EvidenceJson(c.evidence)
      << ", \"cost\": " << Num(c.cost)
      << ", \"chosen\": "
      << (static_cast<int>(k) == d.chosen ? "true" : "false")
      << ", \"rejected\": " << Quote(c.rejected) << "}";
  }
  j << "]}";
  return j.str();
}

}  // namespace depthbias::panel
