// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/flow_jacobian.h"

#include "unseen/util/error.h"

namespace unseen {

Matrix26d ImageMotionJacobianInCamera(const PinholeCamera& camera,
                                      const Eigen::Vector3d& origin_in_cam,
                                      const Eigen::Vector2d& pixel, double depth_m) {
  UNSEEN_CHECK(depth_m > 0.0, "ImageMotionJacobian: depth {} m must be > 0", depth_m);
  const Eigen::Vector3d c = camera.Unproject(pixel, depth_m);
  const double z = c.z();
  Eigen::Matrix<double, 2, 3> proj;
  proj << camera.fx / z, 0.0, -camera.fx * c.x() / (z * z),  //
      0.0, camera.fy / z, -camera.fy * c.y() / (z * z);
  // dc = v_c + w_c x (c - o_c) = [I | -[c - o_c]x] (v_c, w_c)
  Eigen::Matrix<double, 3, 6> motion;
  motion.leftCols<3>().setIdentity();
  motion.rightCols<3>() = -Skew(c - origin_in_cam);
  return proj * motion;
}

Matrix26d ImageMotionJacobian(const PinholeCamera& camera, const Rigid3d& cam_from_world,
                              const Eigen::Vector3d& origin_in_world, const Eigen::Vector2d& pixel,
                              double depth_m) {
  const Eigen::Matrix3d r_cw = cam_from_world.RotationMatrix();
  const Matrix26d j_cam =
      ImageMotionJacobianInCamera(camera, cam_from_world * origin_in_world, pixel, depth_m);
  Matrix26d j;
  j.leftCols<3>() = j_cam.leftCols<3>() * r_cw;
  j.rightCols<3>() = j_cam.rightCols<3>() * r_cw;
  return j;
}

Rigid3d ApplyTwist(const Rigid3d& world_from_obj, const Vector6d& twist) {
  const Eigen::Quaterniond r = ExpSO3(twist.tail<3>()) * world_from_obj.rotation();
  return Rigid3d(r, world_from_obj.translation() + twist.head<3>());
}

}  // namespace unseen
