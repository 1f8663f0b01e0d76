// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Motion segmentation (SPEC 4.2, thesis 2.2.1): the frame divided into regions that move
// under one motion, each a candidate object for the region selection (region_selection.h).
// As in the thesis, the image is cut into blocks (8×8 px) and each block's motion is the
// mean of a dense optical flow over it — OpenCV's DIS flow (Kroeger et al. 2016), the
// well-kept real-time choice. A block moves when its flow exceeds a threshold (and, with
// an interest map, when enough of it is of interest); adjacent moving blocks whose flows
// agree — within an absolute tolerance or a share of their speed, so that a turning object,
// whose flow changes smoothly across it, stays whole — are joined (union-find), and regions
// of too few blocks are dropped. Where the camera itself moves, the dominant motion (the
// median flow of all blocks) can be taken out first.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/video/tracking.hpp>

#include "unseen/camera/camera.h"

namespace unseen {

struct MotionSegmentationOptions {
  int block_px = 8;             // side of the blocks, pixels (thesis: 8)
  double min_motion_px = 0.25;  // a block moves when its mean flow exceeds this, px/frame
  // Two adjacent moving blocks move alike when their flows differ by less than
  // max_difference_px or by less than relative_difference of the faster one's speed.
  double max_difference_px = 1.0;
  double relative_difference = 0.35;
  int min_blocks = 4;  // regions of fewer blocks are dropped
  // A block's flow is trusted only where the image has texture in two directions: the
  // block's mean smaller eigenvalue of the 3×3 structure tensor of grey levels in [0, 1]
  // (cv::cornerMinEigenVal) must exceed this; elsewhere (a white wall) the flow is only the
  // spread of its neighbours' and the block never moves by itself.
  double min_texture = 1e-4;
  // With an interest map: a block counts only when this share of its pixels is of
  // interest (S > 0.5).
  double min_interest_share = 0.0;
  // Subtract the median flow of all blocks first (a moving camera); off for a static one.
  bool remove_dominant_motion = false;
  void Check() const;
};

class MotionSegmenter {
 public:
  explicit MotionSegmenter(const MotionSegmentationOptions& options = {});

  // Takes the next frame (CV_32FC3 BGR [0, 1] or CV_8UC3, the same size every time) and
  // returns its regions: CV_32SC1 labels 1..n of the frame's size, 0 elsewhere; all zero
  // for the first frame (no motion yet). `interest` (CV_32FC1 [0, 1] of the same size, or
  // empty) restricts the moving blocks. Throws unseen::Error for another type or size.
  cv::Mat Segment(const cv::Mat& image, const cv::Mat& interest = cv::Mat());

  // The last dense flow (CV_32FC2, previous -> current frame, px), empty before the
  // second frame; and the number of regions of the last Segment.
  const cv::Mat& flow() const { return flow_; }
  // A region's box (e.g. RegionCandidate::box) brought in by half a block on each side:
  // the blocks along a moving object's outline are only partly on it, and the dense flow
  // spreads a little over the background beside it (measured: about a block in all).
  PixelRect ObjectBox(const PixelRect& region_box) const;
  int num_regions() const { return num_regions_; }

 private:
  MotionSegmentationOptions options_;
  cv::Ptr<cv::DISOpticalFlow> dis_;
  cv::Mat previous_;  // CV_8UC1 grey
  cv::Mat flow_;
  int num_regions_ = 0;
};

}  // namespace unseen
