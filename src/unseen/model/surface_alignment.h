// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Aligning new surface data to the model in use before it replaces it (SPEC 5.4, beyond
// the thesis): a model rebuilt at the tracked pose inherits that pose's error, and the
// object frame drifts by it at every rebuild. The measured depth of the new frame is
// brought onto the model in use, rendered at the tracked pose, by point-to-plane ICP with
// projective association; the new model is then built in the corrected frame, so the
// object frame stays where the first model put it.
#pragma once

#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/mesh/mesh.h"

namespace unseen {

struct SurfaceAlignmentOptions {
  int iterations = 20;
  double max_distance_m = 0.02;    // pairs farther apart along the normal are not the same surface
  double huber_m = 0.002;          // robust kernel width (sensor noise ~1-3 mm at 0.5 m)
  int min_points = 100;            // pairs needed
  double damping = 1e-3;           // Levenberg damping (share of the mean diagonal): unobservable
                                   // motions (a turn of a sphere) stay put
  double max_correction_m = 0.03;  // a larger shift (or turn) is not trusted
  double max_correction_deg = 15.0;
  void Check() const;
};

struct SurfaceAlignment {
  bool ok = false;
  // Applied to the measured points (camera frame), it puts them on the model.
  Rigid3d cam_correction;
  // How far the correction moves the measured surface: the displacement of its centroid
  // (the rotation is about the camera, so the translation alone says little).
  double shift_m = 0.0;
  int pairs = 0;
  double rms_before_m = 0.0, rms_after_m = 0.0;
};

// `depth` CV_32FC1 of `camera`'s size (metres, 0 = none), used inside `mask` (CV_8UC1,
// non-zero; empty: everywhere); `model` seen at `cam_from_obj`.
SurfaceAlignment AlignSurfaceToModel(const cv::Mat& depth, const cv::Mat& mask,
                                     const PinholeCamera& camera, const Mesh& model,
                                     const Rigid3d& cam_from_obj,
                                     const SurfaceAlignmentOptions& options);

}  // namespace unseen
