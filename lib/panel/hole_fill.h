#pragma once
// Holes enclosed by observations take the class of the nearest observation (panel_fit.cpp's
// evidence by area): a hole within fill_px observed pixels on both sides along its row or its
// column is filled, so that each surface counts by the area it covers, not by how many samples
// its texture gave.
//
// Two implementations of the same rule, kept side by side (lib/panel/README.md compares them):
//  - kOpenCv (default): the enclosure from four directional dilations (cv::dilate with a line
//    kernel anchored at one end), the label from cv::distanceTransform with DIST_LABEL_PIXEL: the
//    nearest observed pixel in any direction (L2, 5×5 mask);
//  - kSweeps: four directional sweeps, the label of the nearest observation along the enclosing
//    row or column.
// They differ only in which observation a filled hole takes its label from where the nearest one
// in any direction is not on its row or column.

#include <cstdint>
#include <vector>

namespace depthbias::panel {

enum class HoleFill { kOpenCv, kSweeps };

// labels: width × height, row-major, 0 for no observation, else an observed class (1..255).
// Returns the labels with the enclosed holes filled.
std::vector<std::uint8_t> FillEnclosedHoles(const std::vector<std::uint8_t>& labels, int width,
                                            int height, int fill_px, HoleFill method);

}  // namespace depthbias::panel
