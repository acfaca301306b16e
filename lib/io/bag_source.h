#pragma once
// A recording's depth frames from a RealSense bag, as a records::FrameSource: what a stage that
// reads frames takes, so the stage itself never touches a file. Rewind opens the bag again.

#include <memory>
#include <string>

#include "io/bag.h"
#include "records/frame_source.h"

namespace depthbias::io {

class BagSource : public records::FrameSource {
 public:
  explicit BagSource(std::string path) : path_(std::move(path)) { Rewind(); }  // throws BagError
  const BagInfo& info() const { return reader_->info(); }
  bool Next(records::DepthFrame* frame) override { return reader_->Next(frame); }
  bool Rewind() override {
    reader_ = std::make_unique<BagReader>(path_);
    return true;
  }

 private:
  std::string path_;
  std::unique_ptr<BagReader> reader_;
};

}  // namespace depthbias::io
