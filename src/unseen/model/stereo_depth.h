// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Two-camera stereo (SPEC 5.1, the thesis's stated wish): the reference camera and one
// other are rectified (cv::stereoRectify), matched by semi-global matching
// (cv::StereoSGBM, left-right consistency and speckle filtering), and the disparities'
// points carried back into the reference camera as its depth map. The pair is ordered so
// that the matcher's left image is the camera on the left of the rectified baseline,
// whichever of the two is the reference.
#pragma once

#include "unseen/model/depth_extraction.h"

namespace unseen {

class StereoDepth : public DepthSource {
 public:
  // Throws unseen::Error for a rig without a second camera, an unknown
  // StereoOptions::other_camera, or cameras whose rectification fails.
  StereoDepth(const Rig& rig, int reference, const DepthExtractionOptions& options);
  DepthMap Extract(const Frame& frame, const PixelRect& roi, double near_m = 0.0,
                   double far_m = 0.0) const override;
  DepthSourceKind kind() const override { return DepthSourceKind::kStereo; }
  int other_camera() const { return other_; }

 private:
  Rig rig_;
  int reference_;
  int other_ = -1;
  DepthExtractionOptions options_;
};

}  // namespace unseen
