// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The 6-DoF optical-flow equation, SPEC 3.1.1 (4.1)-(4.5), in its exact form. A surface
// point p (world) of the object moves with the twist (v, w) of the object about its own
// origin o: dp = v + w x (p - o). In a camera with c = R_cw p + t_cw, dc = R_cw dp, and the
// pixel moves by
//     u = fx (dcx cz - cx dcz) / cz^2,    w = fy (dcy cz - cy dcz) / cz^2,
// where cz is the depth of the visible surface read from the rendered depth map. The pose
// update for a twist is (4.7): t += v, R = exp([w]x) R (about the object's origin, in the
// world frame).
#pragma once

#include <Eigen/Core>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"

namespace unseen {

using Matrix26d = Eigen::Matrix<double, 2, 6>;

// d(pixel)/d(v, w) for the pixel `pixel` (pixels of `camera`) whose visible surface point
// has camera-frame depth `depth_m` (> 0), for a world-frame twist (v [m], w [rad]) of the
// object about its origin `origin_in_world`. `cam_from_world` places the camera.
Matrix26d ImageMotionJacobian(const PinholeCamera& camera, const Rigid3d& cam_from_world,
                              const Eigen::Vector3d& origin_in_world, const Eigen::Vector2d& pixel,
                              double depth_m);

// The same for a twist expressed in the camera frame (v_c = R_cw v, w_c = R_cw w) about the
// object origin `origin_in_cam`. ImageMotionJacobian = this * blockdiag(R_cw, R_cw).
Matrix26d ImageMotionJacobianInCamera(const PinholeCamera& camera,
                                      const Eigen::Vector3d& origin_in_cam,
                                      const Eigen::Vector2d& pixel, double depth_m);

// One brightness-constancy row  a . (v_c, w_c) = -It  for image gradient (gx, gy)
// (intensity per pixel) at pixel (x, y) with depth z (metres): a = (n, (c - o) x n) with
// n = J_proj^T g = (fx gx / z, fy gy / z, -(gx (x - cx) + gy (y - cy)) / z) and c the
// back-projected point. Single precision; the hot loop of the solver.
inline void FlowRowInCamera(float fx, float fy, float cx, float cy, const float origin_in_cam[3],
                            float x, float y, float z, float gx, float gy, float row[6]) {
  const float inv_z = 1.0f / z;
  const float dx = x - cx, dy = y - cy;
  const float n0 = fx * gx * inv_z, n1 = fy * gy * inv_z, n2 = -(gx * dx + gy * dy) * inv_z;
  const float p0 = dx / fx * z - origin_in_cam[0];
  const float p1 = dy / fy * z - origin_in_cam[1];
  const float p2 = z - origin_in_cam[2];
  row[0] = n0;
  row[1] = n1;
  row[2] = n2;
  row[3] = p1 * n2 - p2 * n1;
  row[4] = p2 * n0 - p0 * n2;
  row[5] = p0 * n1 - p1 * n0;
}

// Pose update (4.7): world_from_obj with t += v and R = exp([w]x) R. `twist` = (v, w),
// metres and radians, world frame.
Rigid3d ApplyTwist(const Rigid3d& world_from_obj, const Vector6d& twist);

}  // namespace unseen
