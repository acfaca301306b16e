#include "panel/hole_fill.h"

#include <algorithm>
#include <cstddef>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace depthbias::panel {
namespace {

std::vector<std::uint8_t> FillBySweeps(const std::vector<std::uint8_t>& label, int bw, int bh,
                                       int fill_px) {
  constexpr std::int16_t kFar = 1000;
  // Distance to and label of the nearest labelled pixel in each of four directions.
  std::vector<std::int16_t> dist[4];
  std::vector<std::uint8_t> near[4];
  for (int k = 0; k < 4; ++k) {
    dist[k].assign(label.size(), kFar);
    near[k].assign(label.size(), 0);
  }
  auto scan = [&](int k, std::size_t start, std::ptrdiff_t step, int count) {
    std::int16_t d = kFar;
    std::uint8_t l = 0;
    std::size_t b = start;
    for (int n = 0; n < count; ++n, b += step) {
      if (label[b]) {
        d = 0;
        l = label[b];
      } else if (d < kFar) {
        ++d;
      }
      dist[k][b] = d;
      near[k][b] = l;
    }
  };
  for (int y = 0; y < bh; ++y) {
    scan(0, static_cast<std::size_t>(y) * bw, 1, bw);            // from the left
    scan(1, static_cast<std::size_t>(y) * bw + bw - 1, -1, bw);  // from the right
  }
  for (int x = 0; x < bw; ++x) {
    scan(2, x, bw, bh);  // from above
    scan(3, static_cast<std::size_t>(bh - 1) * bw + x, -static_cast<std::ptrdiff_t>(bw), bh);
  }
  std::vector<std::uint8_t> out = label;
  for (std::size_t b = 0; b < label.size(); ++b) {
    if (label[b]) continue;
    int best = kFar;
    for (int axis = 0; axis < 2; ++axis) {
      const int a = 2 * axis, c = a + 1;
      if (dist[a][b] > fill_px || dist[c][b] > fill_px) continue;
      const int k = dist[a][b] <= dist[c][b] ? a : c;
      if (dist[k][b] < best) {
        best = dist[k][b];
        out[b] = near[k][b];
      }
    }
  }
  return out;
}

std::vector<std::uint8_t> FillByOpenCv(const std::vector<std::uint8_t>& label, int bw, int bh,
                                       int fill_px) {
  const cv::Mat lab(bh, bw, CV_8U, const_cast<std::uint8_t*>(label.data()));
  cv::Mat observed;
  cv::compare(lab, 0, observed, cv::CMP_NE);
  // Observed within fill_px to the left / right / above / below (the border is not observed).
  auto within = [&](cv::Size size, cv::Point anchor) {
    cv::Mat d;
    cv::dilate(observed, d, cv::getStructuringElement(cv::MORPH_RECT, size), anchor);
    return d;
  };
  const cv::Mat left = within({fill_px + 1, 1}, {fill_px, 0});
  const cv::Mat right = within({fill_px + 1, 1}, {0, 0});
  const cv::Mat above = within({1, fill_px + 1}, {0, fill_px});
  const cv::Mat below = within({1, fill_px + 1}, {0, 0});
  const cv::Mat enclosed = (left & right) | (above & below);
  // The nearest observed pixel of every hole: its label indexes the observed pixels.
  cv::Mat holes, dist, nearest;
  cv::compare(lab, 0, holes, cv::CMP_EQ);
  std::vector<std::uint8_t> out = label;
  if (cv::countNonZero(observed) == 0) return out;
  cv::distanceTransform(holes, dist, nearest, cv::DIST_L2, cv::DIST_MASK_5,
                        cv::DIST_LABEL_PIXEL);
  std::vector<std::uint8_t> class_of(static_cast<std::size_t>(bw) * bh + 1, 0);
  for (int y = 0; y < bh; ++y) {
    const std::uint8_t* l = lab.ptr<std::uint8_t>(y);
    const int* n = nearest.ptr<int>(y);
    for (int x = 0; x < bw; ++x)
      if (l[x]) class_of[static_cast<std::size_t>(n[x])] = l[x];
  }
  for (int y = 0; y < bh; ++y) {
    const std::uint8_t* e = enclosed.ptr<std::uint8_t>(y);
    const int* n = nearest.ptr<int>(y);
    std::uint8_t* o = out.data() + static_cast<std::size_t>(y) * bw;
    for (int x = 0; x < bw; ++x)
      if (!o[x] && e[x]) o[x] = class_of[static_cast<std::size_t>(n[x])];
  }
  return out;
}

}  // namespace

std::vector<std::uint8_t> FillEnclosedHoles(const std::vector<std::uint8_t>& labels, int width,
                                            int height, int fill_px, HoleFill method) {
  if (labels.empty() || width <= 0 || height <= 0) return labels;
  return method == HoleFill::kOpenCv ? FillByOpenCv(labels, width, height, fill_px)
                                     : FillBySweeps(labels, width, height, fill_px);
}

}  // namespace depthbias::panel
