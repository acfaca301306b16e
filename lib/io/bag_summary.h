#pragma once
// Human-readable and JSON summaries of a bag's BagInfo (what bag_info prints).

#include <string>

#include "io/bag.h"

namespace depthbias::io {

// Several lines, like `rosbag info` for the RealSense layout.
std::string BagSummaryText(const BagInfo& info);

// One JSON object on one line: file, compressed, indexed, streams[], depth{topic, intrinsics
// {width,height,fx,fy,ppx,ppy,model,coeffs}, depth_units, frames, first_timestamp_ms,
// last_timestamp_ms}, options{name: value}, device{name, serial, firmware, all: {...}}.
std::string BagSummaryJson(const BagInfo& info);

// {"file": ..., "error": ...} on one line.
std::string BagErrorJson(const std::string& file, const std::string& error);

// Shortest decimal text that reads back to the same value (as float when the value is one).
std::string FormatNumber(double value);

}  // namespace depthbias::io
