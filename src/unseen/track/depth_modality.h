// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The depth modality: whenever a frame carries a depth image (RGB-D cameras, registered to
// the colour camera), the rendered surface is aligned with the measured one by robust
// point-to-plane distances, in the same Gauss-Newton step as the photometric rows
// (flow_solver.h, SolveJoint). A rendered pixel x with surface point p (camera frame, from
// the render's depth) and normal n is paired with the measured point q at the pixel where p
// projects in the full-resolution camera (projective association). Under the object twist
// (v, w) about its origin o, p moves by v + w x (p - o), so the row is
//     a = (n, (p - o) x n),   b = n . (q - p),
// the same form as the optical-flow row (flow_jacobian.h). Normals come from the rendered
// depth map (central differences of the back-projected points), exact on flat faces.
#pragma once

#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/track/flow_solver.h"
#include "unseen/track/modality.h"

namespace unseen {

struct DepthModalityOptions {
  bool enabled = true;  // used whenever the frame carries depth
  // Rendered pixels are sampled on a regular grid with at most this many per camera and
  // round (the grid's step follows the rendered area).
  int max_points = 800;
  // Pairs whose measured depth differs from the rendered one by more than this along the
  // ray are no correspondence (another surface), metres at level 0; the gate doubles at
  // each coarser pyramid level (whose start may be further off).
  double max_distance_m = 0.03;
  // Pairs whose measured surface is nearer than the rendered one by more than this (an
  // occluder in front: a hand holding the object) give no row, unless more than half of
  // the measured points are (the pose is behind the measured surface: every row pulls it
  // forward); 0: off. Kept within the gate, a finger lying across a box's face pulled the
  // face towards itself and turned the box 25 deg at the first frame (held-out
  // box_held_fingers, 18.3 -> 100 %); a whole hand's fingers (16-18 mm thick, over half
  // of the face: box_held_hand) lie 9-18 mm in front, and at 15 mm the box settled 19 deg
  // turned into them (0 -> 100 % at 8 mm, with the two terms below).
  double occluder_margin_m = 0.008;
  // ... and at least this many times the sensor's noise: far from the sensor, where the
  // noise is of that size, a fixed margin cut the noise's near side only and pushed the
  // object away (held-out box at 1.7 m, 17 mm of noise: 78 -> 70 %). The noise is the
  // pairs' robust spread, at most roughness_noise_factor times the measured surface's
  // roughness between neighbouring pixels: the spread also counts the pose's error and the
  // occluder itself (over half of a face in front, it raised the margin past the hand),
  // the roughness only the sensor's noise independent from pixel to pixel (about half of
  // it on the renders' sensor model, whose noise is half spatially correlated).
  double occluder_margin_sigmas = 3.0;
  double roughness_noise_factor = 3.0;
  // ... and at least the rendered depth's change across this many pixels: on a steep or
  // grazing surface (a cube's top face seen from the front) a pixel or two of
  // misregistration between the depth and the colour image, or of the pose, measures the
  // surface that much nearer with no occluder (the real cube: those rows level it;
  // without, at an 8 mm margin, 4.83 -> 5.12 mm, 2.42 -> 2.65 deg on its trusted frames).
  double occluder_slope_px = 4.0;
  // Robust kernel, scales and weight against the other modalities; residuals in metres.
  // The weight makes up for the photometric rows' count: thousands of pixels whose errors
  // are correlated (the blur spreads one edge over several) would otherwise outvote a few
  // hundred independent depth measurements (30 measured best on real RGB-D footage).
  ResidualModel residual{RobustKernel::kTukey, 4.685, /*min_scale=*/0.002,
                         /*min_noise=*/0.002, /*weight=*/30.0};
  // Confidence: a sampled point agrees when its measured depth is within agree_distance_m
  // of the rendered one, and is hidden (an occluder in front) when the measured surface is
  // nearer by more than that. The depth term of the confidence ramps from 0 at
  // bad_agreement to 1 at good_agreement of the share of agreeing points among the visible
  // (not hidden) measured ones; with fewer than min_measured measured points depth does not
  // judge the frame, and with more than max_hidden_share of them hidden it judges it bad
  // (the object hidden, or the pose far behind it).
  double agree_distance_m = 0.01;
  double bad_agreement = 0.3;
  double good_agreement = 0.7;
  int min_measured = 30;
  double max_hidden_share = 0.8;
  // Whether the depth rows join the coarse levels' solves while the photometric modality
  // leads with the model's own texture (not colours projected from frames, not demoted):
  // off by default, so those levels bring the pose as far as the texture says and the depth
  // joins at the finest level. A real sensor's depth sits a few millimetres off its colour
  // image; at the coarse levels its rows held the pose where they agreed, the joint updates
  // were half as long as the texture's alone and the levels stopped short of a fast motion
  // (the real RGB-D cube every second frame, 15 fps: 74 -> 94 % within 5 cm / 5 deg, every
  // third 42 -> 52 %, every fourth 48 -> 60 %; at 30 fps 100 % either way). An untextured
  // model, or one whose colours were projected from frames (the on-line model, a live
  // appearance), keeps its depth rows at every level: there the texture is not the better
  // guide (the on-line untextured teapot fell 98 -> 90 % without them).
  bool coarse_with_own_texture = false;
  // Without them, a tracked frame that comes out doubtful (below
  // ReacquisitionOptions::doubtful_confidence) is aligned again with the depth rows at every
  // level and the more confident result kept: blurred fast frames whose texture led the
  // coarse levels astray (the real cube every third frame 52 -> 58 %, the box at 1.7 m
  // 77 -> 78 %).
  bool retry_doubtful_with_coarse_depth = true;
  void Check() const;
};

// What the depth rows of one round saw (summed over cameras as needed).
struct DepthCounts {
  long sampled = 0;   // rendered pixels sampled
  long measured = 0;  // with a measured depth
  long agreeing = 0;  // measured within agree_distance_m
  long hidden = 0;    // measured nearer than the render by more than agree_distance_m
  long used = 0;      // gave a row (within the gate, with a normal)
  DepthCounts& operator+=(const DepthCounts& o);
  // Share of agreeing points among the measured, not hidden ones; 0 when nearly all are
  // hidden; -1 when depth cannot judge (too few measured points).
  double Agreement(const DepthModalityOptions& options) const;
};

// One camera at one pyramid level.
struct DepthModalityInput {
  const cv::Mat* rendered_depth = nullptr;  // CV_32FC1 metres (0 = no surface), size of roi
  PixelRect roi;                            // level pixels of rendered_depth's (0, 0)
  PinholeCamera level_camera;               // the level's camera
  int level = 0;
  const cv::Mat* measured_depth = nullptr;  // CV_32FC1 metres at full resolution, 0 = none
  PinholeCamera camera;                     // the full-resolution camera of measured_depth
  Eigen::Vector3d origin_in_cam = Eigen::Vector3d::Zero();  // object origin, camera frame
};

// Appends the point-to-plane rows of the sampled pixels to `out` (rows in the camera frame,
// inv_grad_norm = 1: residuals in metres) and adds to `counts`.
void AddDepthEquations(const DepthModalityInput& input, const DepthModalityOptions& options,
                       FlowEquations* out, DepthCounts* counts);

// The depth modality behind the Modality interface: rows for the cameras whose round has
// measured depth.
class DepthModality : public CountingModality<DepthCounts> {
 public:
  explicit DepthModality(const DepthModalityOptions& options = {})
      : CountingModality("depth"), options_(options) {
    residual_model() = options.residual;
  }
  void AddEquations(const ModalityRound& round) override;

 private:
  DepthModalityOptions options_;
};

}  // namespace unseen
