// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// What the complete system saw and did in one frame, drawn over the reference camera's
// image (SPEC 6's overlay): the interest map as a red tint, the candidate regions (thin
// yellow boxes) and the selected one (cyan), the model's outline and axes at the tracked
// pose (green while tracking, red when lost) and a status line.
#pragma once

#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/mesh/mesh.h"
#include "unseen/system/system.h"

namespace unseen {

struct SystemOverlayOptions {
  double interest_alpha = 0.5;  // tint strength at interest 1, [0, 1]
  int line_thickness_px = 2;    // >= 1
  double axis_share = 0.6;      // axis length, share of the model's bounding radius (>= 0)
  double font_scale = 0.6;      // > 0
  void Check() const;
};

// Draws `step` over `image` (CV_8UC3 BGR of the reference camera, or CV_32FC3 in [0, 1],
// converted to CV_8UC3 in place). `model` (object frame, metres) is drawn at the tracked
// pose when the step has one; null draws no model. `cam_from_world`: the reference camera.
void DrawSystemOverlay(const SystemStep& step, const Mesh* model, const PinholeCamera& camera,
                       const Rigid3d& cam_from_world, const SystemOverlayOptions& options,
                       cv::Mat* image);

}  // namespace unseen
