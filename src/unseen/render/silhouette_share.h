// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// How much of an object's silhouette a camera's image holds: the part of the object that
// has moved past the image border is not lost, only out of view.
#pragma once

#include <Eigen/Core>
#include <span>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/mesh/mesh.h"

namespace unseen {

// Share, in [0, 1], of the silhouette of `mesh` at `cam_from_obj` that falls inside the
// image of `camera`. The box `box_corners_in_obj` (the model's, object frame) decides
// cheaply: projected wholly inside the image, the share is 1. Otherwise the whole
// silhouette is rendered into a camera that sees it all, at most `max_side_px` pixels on
// its longer side (the mask alone), and its pixels inside the image counted. 1 as well when
// a box corner is not in front of the camera (no whole silhouette to compare with), 0 when
// the silhouette covers no pixel of that render.
double SilhouetteShareInImage(const Mesh& mesh, const PinholeCamera& camera,
                              const Rigid3d& cam_from_obj,
                              std::span<const Eigen::Vector3d, 8> box_corners_in_obj,
                              int max_side_px = 64);

}  // namespace unseen
