// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Every setting of the 6-DoF tracker (SPEC 3) in one struct, with the thesis's values as
// defaults, validated once by Check() and loadable from YAML:
//
//   preprocess: {use_linf: true, linf_sigma_px: 8, linf_epsilon: 0.05, blur_sigma_px: 1.8}
//   selection:  {color_mode: redundancy, min_gradient_sq: 984e-6, max_normal_flow_px: 1.22,
//                use_occlusion_rejection: true, block_min_share_ratio: 0.5, ...}
//   solver:     {kernel: huber, kernel_width: 1.345, irls_iterations: 2}
//   pyramid:    {max_levels: 4, min_object_px: 32, max_iterations_per_level: 6}
//   predictor:  {type: kalman, linear_accel_sigma: 2.0, min_confidence: 0.5}
//   failure:    {lost_confidence: 0.25, lost_after_frames: 2, recover_confidence: 0.5,
//                good_used_px: 2500, bad_residual_ratio: 1.75, ...}
//   frame_interval_s: 0.0333
#pragma once

#include <string>

#include "unseen/track/flow_solver.h"
#include "unseen/track/motion_predictor.h"
#include "unseen/track/pixel_selection.h"
#include "unseen/track/preprocess.h"

namespace unseen {

// Multi-scale alignment (SPEC 3.3) and the Gauss-Newton iterations at each level.
struct PyramidOptions {
  int max_levels = 4;             // cap on pyramid levels (the thesis saw oscillation with more)
  // The coarsest level keeps the object's bounding sphere at least this wide, pixels; so
  // the number of levels follows the object's on-screen size (3.3).
  double min_object_px = 32.0;
  int max_iterations_per_level = 6;  // render-solve-update rounds per level (3.9)
  double min_update_px = 0.1;     // a level is done when an update moves the object less, px
  // Coarser levels (level > 0) only need to bring the pose within the capture range of the
  // next finer level, so they stop earlier: at most this many rounds, and once an update
  // moves the object less than coarse_min_update_px (pixels of that level). Each round
  // costs a render and a pre-processing of the virtual image.
  int coarse_max_iterations = 6;
  double coarse_min_update_px = 0.3;
  double max_step_px = 4.0;       // one update moves the object at most this far, level px
  int rim_px = 3;                 // blurred rim around the rendered mask that is used, px
  // Levels finer than this are rendered 2x2 supersampled, so that the virtual image has the
  // area-averaged silhouette and texture of a camera image (a point-sampled silhouette pasted
  // over the input biases the pose outwards by about a quarter pixel).
  int supersampled_levels = 8;
  void Check() const;
};

// Tracking-failure detection (SPEC 3.9). The confidence of a frame is the product of
//  * the support: the better of the share of rendered-gradient pixels that survive the
//    consistency tests, mapped linearly from [min_share, good_share] to [0, 1], and the
//    absolute number of used pixels, from [min_used_px, good_used_px] to [0, 1] (a partly
//    occluded object whose visible part still gives thousands of equations is supported);
//  * the RMS normal-flow residual before the last update, from [good_residual_px,
//    bad_residual_px] to [1, 0], and its ratio to the residual of the recent confident
//    frames (the noise and model-error floor of this camera and object), from
//    [good_residual_ratio, bad_residual_ratio] to [1, 0]: a misaligned pose keeps fewer
//    but worse-fitting pixels, an occluded but aligned one fits as well as before;
//  * the size of the last update at the finest level (not converged = doubtful), from
//    [good_update_px, bad_update_px] to [1, 0];
// and 0 with fewer than min_pixels equations.
struct FailureOptions {
  double min_share = 0.15;
  double good_share = 0.5;
  double min_used_px = 500;     // used pixels (all cameras)
  double good_used_px = 2500;
  double good_residual_px = 0.3;
  double bad_residual_px = 0.9;
  double good_residual_ratio = 1.25;  // residual / reference residual
  double bad_residual_ratio = 1.75;
  // Weight of a new confident frame in the running reference residual (exponential mean),
  // and its floor: below it the fit is at the level of interpolation error, where a
  // doubling means nothing (noiseless renders), px.
  double residual_reference_rate = 0.1;
  double min_reference_residual_px = 0.2;
  double good_update_px = 0.3;
  double bad_update_px = 2.0;
  int min_pixels = 40;
  double lost_confidence = 0.25;   // a frame below this is bad
  int lost_after_frames = 2;       // this many bad frames in a row: lost (hysteresis)
  double recover_confidence = 0.5; // while lost, a frame above this re-acquires
  bool search_when_lost = true;    // try poses around the last good one while lost
  double search_offset = 0.5;      // search step, in bounding-sphere radii
  void Check() const;
};

struct TrackerOptions {
  PreprocessOptions preprocess;
  PixelSelectionOptions selection;
  FlowSolverOptions solver;
  PyramidOptions pyramid;
  MotionPredictorOptions predictor;
  FailureOptions failure;
  double frame_interval_s = 1.0 / 30.0;  // time between frames for the predictor, s
  void Check() const;
};

// Reads a YAML file of the layout above over the defaults; absent keys keep their default.
// Throws unseen::Error naming the file and the key for an unreadable file, an unknown key,
// a value of the wrong type or one that fails Check().
TrackerOptions LoadTrackerOptions(const std::string& path);
// The same from YAML text; `what` names the source in messages.
TrackerOptions ParseTrackerOptions(const std::string& yaml_text,
                                   const std::string& what = "tracker options");

}  // namespace unseen
