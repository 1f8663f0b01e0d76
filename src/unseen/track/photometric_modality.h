// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The photometric modality, the thesis's tracker (SPEC 3.1): the optical flow between the
// pre-processed virtual image (the model rendered at the round's pose over the input) and
// the input image, at the pixels that pixel selection (pixel_selection.h) keeps.
#pragma once

#include "unseen/track/modality.h"
#include "unseen/track/pixel_selection.h"

namespace unseen {

class PhotometricModality : public CountingModality<SelectionCounts> {
 public:
  // `remeasure_margin_px`: MoveBy measures again only the equations at least this far
  // (level pixels) inside the rendered silhouette.
  explicit PhotometricModality(const PixelSelectionOptions& options = {},
                               int remeasure_margin_px = 0)
      : CountingModality("photometric"), options_(options),
        remeasure_margin_px_(remeasure_margin_px) {}
  void BeginRound(int num_cameras) override;
  void AddEquations(const ModalityRound& round) override;
  // Measures the brightness differences again at the moved pose: each equation's surface
  // point, moved by the twist, is projected into the round's pre-processed input, which is
  // sampled there (bilinear) against the virtual image's value at the equation's pixel; the
  // rows (the virtual image's gradients) stay. An equation nearer the silhouette than the
  // margin, or whose point leaves the input region, keeps its row's linear model: the
  // virtual image there mixes in the input around the rendered pose (and LINF and the
  // shading transfer were normalised around it), so measured again it would pull back
  // towards that pose. The round's buffers must still hold (the tracker's do until the
  // next round).
  void MoveBy(const std::vector<Vector6d>& twist_in_cam) override;
  // Camera `camera`'s blocks of this round that the block occlusion rejection dropped
  // (SelectPixels' `occluded_blocks`; PixelSelectionOptions::block_px level pixels a side,
  // from the round's roi corner), or null before its AddEquations of this round.
  const cv::Mat* occluded_blocks(int camera) const;
  int block_px() const { return options_.block_px; }

 private:
  // What one camera's round needs to measure again.
  struct CameraRound {
    std::vector<PhotometricSample> samples;  // one per equation
    std::vector<uint8_t> remeasure;          // per equation: inside the margin
    cv::Mat interior;                        // the rendered mask eroded by the margin
    cv::Mat occluded_blocks;                 // SelectPixels' dropped blocks
    // The pre-processed input, of the size of roi; null until AddEquations of this round.
    const cv::Mat* input = nullptr;
    PixelRect roi;
    PinholeCamera camera;
    Eigen::Vector3d origin_in_cam = Eigen::Vector3d::Zero();
  };
  PixelSelectionOptions options_;
  int remeasure_margin_px_ = 0;
  std::vector<CameraRound> rounds_;  // per camera (AddEquations may run concurrently)
};

}  // namespace unseen
