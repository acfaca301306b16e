#pragma once
// A recording's depth frames, in order: what every stage that reads a recording takes, so that
// the library itself never touches a file (apps wrap io::BagReader; tests hold frames in memory).

#include "records/depth_frame.h"

namespace depthbias::records {

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual bool Next(DepthFrame* frame) = 0;  // false at the end
  // Starts again from the first frame; false when the source cannot. The automatic panel mode
  // reads the frames twice (detect, then measure); the box mode once.
  virtual bool Rewind() { return false; }
};

}  // namespace depthbias::records
