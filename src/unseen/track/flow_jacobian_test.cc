// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/flow_jacobian.h"

#include <random>

#include <gtest/gtest.h>

#include "unseen/util/error.h"

namespace unseen {
namespace {

PinholeCamera TestCamera() {
  PinholeCamera cam;
  cam.width = 512;
  cam.height = 256;
  cam.fx = 837.3;
  cam.fy = 820.0;
  cam.cx = 255.5;
  cam.cy = 127.5;
  return cam;
}

// Pixel of the surface point after moving the object by `twist` (4.7).
Eigen::Vector2d MovedPixel(const PinholeCamera& cam, const Rigid3d& cam_from_world,
                           const Eigen::Vector3d& origin, const Eigen::Vector3d& p_world,
                           const Vector6d& twist) {
  const Eigen::Vector3d moved = ExpSO3(twist.tail<3>()) * (p_world - origin) + origin +
                                twist.head<3>();
  return cam.Project(cam_from_world * moved);
}

TEST(FlowJacobian, MatchesNumericDifferentiationOfTheProjection) {
  const PinholeCamera cam = TestCamera();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Rigid3d world_from_cam(ExpSO3(Eigen::Vector3d(u(rng), u(rng), u(rng)) * 0.5),
                                 Eigen::Vector3d(u(rng), u(rng), u(rng)) * 0.3);
    const Rigid3d cam_from_world = world_from_cam.Inverse();
    const Eigen::Vector2d pixel(256 + 200 * u(rng), 128 + 100 * u(rng));
    const double depth = 0.8 + 0.4 * (u(rng) + 1.0);
    const Eigen::Vector3d p_world = world_from_cam * cam.Unproject(pixel, depth);
    const Eigen::Vector3d origin =
        world_from_cam * Eigen::Vector3d(0.05 * u(rng), 0.05 * u(rng), depth + 0.05 * u(rng));
    const Matrix26d j = ImageMotionJacobian(cam, cam_from_world, origin, pixel, depth);
    const double h = 1e-6;
    for (int k = 0; k < 6; ++k) {
      Vector6d d = Vector6d::Zero();
      d(k) = h;
      const Eigen::Vector2d numeric = (MovedPixel(cam, cam_from_world, origin, p_world, d) -
                                       MovedPixel(cam, cam_from_world, origin, p_world, -d)) /
                                      (2 * h);
      EXPECT_NEAR(j(0, k), numeric(0), 1e-4 * (1 + std::abs(numeric(0)))) << "dof " << k;
      EXPECT_NEAR(j(1, k), numeric(1), 1e-4 * (1 + std::abs(numeric(1)))) << "dof " << k;
    }
  }
}

TEST(FlowJacobian, FastRowEqualsGradientTimesJacobian) {
  const PinholeCamera cam = TestCamera();
  const Eigen::Vector3d origin(0.02, -0.01, 1.1);
  const float o[3] = {0.02f, -0.01f, 1.1f};
  const Eigen::Vector2d pixel(300.0, 90.0);
  const double depth = 1.05;
  const Eigen::Vector2d grad(0.07, -0.03);
  const Matrix26d j = ImageMotionJacobianInCamera(cam, origin, pixel, depth);
  const Eigen::Matrix<double, 1, 6> expected = grad.transpose() * j;
  float row[6];
  FlowRowInCamera(float(cam.fx), float(cam.fy), float(cam.cx), float(cam.cy), o, 300.0f, 90.0f,
                  float(depth), float(grad.x()), float(grad.y()), row);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(row[k], expected(k), 1e-4 * (1 + std::abs(expected(k))));
}

TEST(FlowJacobian, ApplyTwistRotatesAboutTheObjectOrigin) {
  const Rigid3d pose(ExpSO3(Eigen::Vector3d(0.1, 0.2, 0.3)), Eigen::Vector3d(0.1, 0.0, 1.0));
  Vector6d twist;
  twist << 0.01, -0.02, 0.03, 0.0, 0.3, 0.0;
  const Rigid3d moved = ApplyTwist(pose, twist);
  EXPECT_TRUE(moved.translation().isApprox(pose.translation() + twist.head<3>()));
  EXPECT_NEAR(AngleBetween(moved.rotation(), pose.rotation()), 0.3, 1e-9);
}

TEST(FlowJacobian, RejectsNonPositiveDepth) {
  EXPECT_THROW(ImageMotionJacobianInCamera(TestCamera(), Eigen::Vector3d(0, 0, 1),
                                           Eigen::Vector2d(1, 1), 0.0),
               Error);
}

}  // namespace
}  // namespace unseen
