// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Pixel selection and equation assembly (SPEC 3.1 step 4, 3.4, 3.6): from the
// pre-processed virtual image Iv and input image Ii of one camera, keep the pixels of the
// rendered object (mask and its blurred rim) that carry usable gradient and pass the
// consistency tests, and turn each into a row of the 6-DoF optical-flow equation (3.1.1).
#pragma once

#include <cstdint>
#include <string>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/track/flow_solver.h"
#include "unseen/track/preprocess.h"

namespace unseen {

// How colour enters the equations.
enum class ColorMode {
  kColorGradientRedundancy,  // 3.6: sign-aligned sum of the channels, one equation a pixel
  kRawColor,                 // one equation per channel (3 per pixel)
  kGrey,                     // luminance only (loses iso-luminant colour edges)
};
const char* ToString(ColorMode mode);  // "redundancy", "raw", "grey"
// Throws unseen::Error naming `what` for an unknown name.
ColorMode ParseColorMode(const std::string& text, const std::string& what = "color_mode");

struct PixelSelectionOptions {
  ColorMode color_mode = ColorMode::kColorGradientRedundancy;
  bool use_gradient_threshold = true;
  // tau of (4.8) on the squared gradient magnitude (lambda1 of 3.6 in the redundancy mode,
  // |grad|^2 of the channel or of the luminance otherwise); intensities in [0, 1], per px^2.
  double min_gradient_sq = 984e-6;
  bool use_normal_flow_bound = true;
  double max_normal_flow_px = 1.22;  // tau_vmax of (4.9), for blur sigma = 1.8 px
  bool use_occlusion_rejection = true;
  double occlusion_min_gradient_sq = 98.4e-6;  // tau_gm of (4.13), squared, per channel
  double occlusion_max_angle_rad = 0.90;       // tau_theta of (4.14), per channel
  double occlusion_max_magnitude_diff = 39.2e-3;  // tau_md of (4.15), |grad| over channels
  double min_eigen_ratio = 10.0;  // lambda1 / lambda2 for a "directed" pixel (3.6)
  // Blocks of block_px x block_px level pixels tally how many of their gradient pixels
  // survive the tests (SelectionCounts::block_share_sum), which tells a coherent occluder
  // (whole blocks rejected, the rest intact) from a misaligned pose (rejections spread over
  // every block). Blocks with fewer than block_min_gradient gradient pixels are not counted.
  int block_px = 8;
  int block_min_gradient = 8;
  // Block occlusion rejection (with use_occlusion_rejection): the pixels of a counted block
  // where the share of gradient pixels passing the occlusion tests (4.13)-(4.15) is below
  // block_min_share_ratio times the median share of the counted blocks are dropped too
  // (those of an occluder that passed the per-pixel tests by chance); 0 disables it. A
  // misaligned pose lowers the share of every block alike, so it drops few blocks; the
  // normal-flow bound (4.9), which a misalignment fails in whole blocks along the
  // silhouette, does not count. It needs at least block_min_blocks counted blocks: the
  // median of a few blocks of a small or coarse image says little.
  double block_min_share_ratio = 0.5;
  int block_min_blocks = 32;
  void Check() const;
};

// SelectionInput::region's values: the rendered object's own pixels, and those of a rim
// outside its silhouette (PyramidOptions::rim_px) that give rows to the solve but are not
// counted: the counts and the blocks below, and all that judges the pose by them, see the
// object's own pixels only, with or without a rim.
constexpr uint8_t kObjectPixel = 255;
constexpr uint8_t kRimPixel = 128;

// How many of the object's pixels each test saw and rejected (summed over cameras/levels
// as needed); SelectionCounts::equations counts the rim's rows too.
struct SelectionCounts {
  long candidates = 0;               // object pixels (kObjectPixel) with a depth
  long rejected_gradient = 0;        // (4.8)
  long rejected_input_gradient = 0;  // (4.13)
  long rejected_direction = 0;       // (4.14)
  long rejected_magnitude = 0;       // (4.15)
  long rejected_undirected = 0;      // 3.6, lambda1 / lambda2 below the ratio
  long rejected_normal_flow = 0;     // (4.9)
  long rejected_block = 0;           // in a block that mostly failed the tests
  long occluded_gradient = 0;        // the object's gradient pixels in those blocks (all)
  long used = 0;                     // pixels that gave at least one equation
  long equations = 0;
  // Over the counted blocks b (PixelSelectionOptions::block_px): the sum of used_b^2 /
  // gradient_b and the sum of used_b. Their ratio is the mean over the used pixels of the
  // survival share of their own block (BlockShare()).
  double block_share_sum = 0.0;
  long block_used = 0;
  // Pixels with rendered gradient, the denominator of the survival share (3.9).
  long gradient_pixels() const { return candidates - rejected_gradient; }
  // Gradient pixels outside the blocks found occluded: the texture the camera can see.
  long visible_gradient_pixels() const { return gradient_pixels() - occluded_gradient; }
  // Mean survival share of the used pixels' blocks in [0, 1]: near the share of a clear
  // view when the rejected pixels are gathered in whole blocks (an occluder), near the
  // overall share when they are spread evenly (a misaligned pose); 0 without blocks.
  double BlockShare() const { return block_used > 0 ? block_share_sum / block_used : 0.0; }
  // How far the rejected pixels gather in whole blocks, [0, 1]: BlockShare() against the
  // overall share s = used / gradient_pixels(), (BlockShare - s) / (1 - s). Near 1 when
  // what was rejected lies in blocks of its own (an occluder), near 0 when rejections are
  // spread evenly over the object (a misaligned pose, a change of light); 0 without blocks
  // or without rejections.
  double RejectionGathering() const;
  SelectionCounts& operator+=(const SelectionCounts& o);
};

// One camera at one pyramid level, all buffers of the size of `roi`.
struct SelectionInput {
  const PreprocessedImage* virtual_image = nullptr;  // with gradients
  const PreprocessedImage* input_image = nullptr;    // gradients needed for occlusion tests
  const cv::Mat* region = nullptr;  // CV_8UC1: kObjectPixel, kRimPixel, 0 where unused
  const cv::Mat* depth = nullptr;   // CV_32FC1, metres, camera-frame z (> 0 where usable)
  PixelRect roi;                    // level pixels: buffer (0, 0) is pixel (roi.x0, roi.y0)
  PinholeCamera camera;             // the level's camera
  Eigen::Vector3d origin_in_cam = Eigen::Vector3d::Zero();  // object origin, camera frame
};

// Where an equation's brightness difference comes from, so that it can be measured again
// after the pose moved without rendering anew (PhotometricModality::MoveBy): the equation's
// right-hand side is -(sum_j weight[j] * Ii_j(x, y) - virtual_value), Ii the pre-processed
// input at the level pixel (x, y) of a surface point at camera-frame depth z.
struct PhotometricSample {
  float x = 0, y = 0, z = 0;        // level pixel, metres
  float weight[3] = {0, 0, 0};      // per BGR channel
  float virtual_value = 0;          // sum_j weight[j] * Iv_j(x, y)
};

// Appends the equations of the selected pixels to `out` (rows in the camera frame, see
// FlowRowInCamera) and adds to `counts`; with `samples`, one PhotometricSample per
// equation appended, in the same order. Tests are applied in the order gradient (4.8),
// occlusion (4.13)-(4.15), directedness (3.6, redundancy mode), normal flow (4.9).
// With `occluded_blocks`, the blocks the block occlusion rejection dropped: CV_8UC1 of
// ceil(h / block_px) x ceil(w / block_px), non-zero where dropped (all zero when the test
// did not run).
void SelectPixels(const SelectionInput& input, const PixelSelectionOptions& options,
                  FlowEquations* out, SelectionCounts* counts,
                  std::vector<PhotometricSample>* samples = nullptr,
                  cv::Mat* occluded_blocks = nullptr);

}  // namespace unseen
