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
  // Rectifies the pair once (it depends on the rig only). Throws unseen::Error for a rig
  // without a second camera, an unknown StereoOptions::other_camera, cameras of different
  // sizes or sharing a centre, or a pair stacked vertically.
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
  // The pair's rectification (reference first, cv::stereoRectify) and its maps.
  Eigen::Matrix3d rect_from_ref_ = Eigen::Matrix3d::Identity();    // R1
  double focal_px_ = 0.0, principal_x_ = 0.0, principal_y_ = 0.0;  // P1
  double focal_baseline_ = 0.0;                                    // focal length x baseline, px m
  // The other camera left of the reference: the pair is matched mirrored, so that the
  // reference is the matcher's left image.
  bool mirrored_ = false;
  cv::Mat ref_map_x_, ref_map_y_, other_map_x_, other_map_y_;  // CV_32FC1, full image
};

}  // namespace unseen
