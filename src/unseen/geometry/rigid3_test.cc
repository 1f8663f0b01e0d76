// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/geometry/rigid3.h"

#include <random>

#include <gtest/gtest.h>

#include "unseen/util/error.h"

namespace unseen {
namespace {

Rigid3d RandomPose(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Rigid3d(Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)),
                 Eigen::Vector3d(n(rng), n(rng), n(rng)));
}

TEST(Rigid3d, ComposeAndInverse) {
  std::mt19937 rng(1);
  for (int i = 0; i < 50; ++i) {
    const Rigid3d a = RandomPose(rng), b = RandomPose(rng);
    const Eigen::Vector3d p(0.3, -1.2, 2.0);
    EXPECT_TRUE(((a * b) * p - a * (b * p)).isZero(1e-12));
    EXPECT_TRUE(((a * a.Inverse()).ToMatrix() - Eigen::Matrix4d::Identity()).isZero(1e-12));
    EXPECT_TRUE(((a * b).ToMatrix() - a.ToMatrix() * b.ToMatrix()).isZero(1e-12));
  }
}

TEST(Rigid3d, ExpLogRoundTrip) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 100; ++i) {
    Vector6d x;
    for (int k = 0; k < 6; ++k) x(k) = u(rng);
    x.tail<3>() *= (i % 4 == 0) ? 1e-9 : 2.5;  // tiny rotations and large ones (< pi)
    if (x.tail<3>().norm() >= 3.1) continue;
    const Vector6d y = Rigid3d::Exp(x).Log();
    EXPECT_TRUE((x - y).isZero(1e-9)) << x.transpose() << " vs " << y.transpose();
  }
}

TEST(Rigid3d, ExpMatchesMatrixExponentialForSmallTwist) {
  // For a pure rotation, Exp rotates about the origin; the translation part follows V(w).
  Vector6d x = Vector6d::Zero();
  x(5) = M_PI / 2;
  const Rigid3d r = Rigid3d::Exp(x);
  EXPECT_TRUE((r * Eigen::Vector3d(1, 0, 0) - Eigen::Vector3d(0, 1, 0)).isZero(1e-12));
  x << 1, 2, 3, 0, 0, 0;
  EXPECT_TRUE((Rigid3d::Exp(x).translation() - Eigen::Vector3d(1, 2, 3)).isZero(1e-15));
}

TEST(Rigid3d, RejectsNonRotations) {
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  r(0, 0) = 1.1;
  EXPECT_THROW(Rigid3d::FromRotationMatrix(r, Eigen::Vector3d::Zero(), "gt frame 3"), Error);
  r = -Eigen::Matrix3d::Identity();
  EXPECT_THROW(Rigid3d::FromRotationMatrix(r, Eigen::Vector3d::Zero()), Error);
  r = Eigen::Matrix3d::Identity();
  r(1, 2) = std::nan("");
  EXPECT_THROW(Rigid3d::FromRotationMatrix(r, Eigen::Vector3d::Zero()), Error);
  EXPECT_THROW(Rigid3d(Eigen::Quaterniond(0, 0, 0, 0), Eigen::Vector3d::Zero()), Error);
  try {
    Rigid3d::FromRotationMatrix(2.0 * Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(),
                                "scene_gt.json frame 7");
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("scene_gt.json frame 7"), std::string::npos);
  }
}

TEST(Rigid3d, InterpolateEndsAndMiddle) {
  const Rigid3d a(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 0));
  Vector6d x;
  x << 2, 0, 0, 0, 0, 1.0;
  const Rigid3d b(ExpSO3(Eigen::Vector3d(0, 0, 1.0)), Eigen::Vector3d(2, 0, 0));
  const Rigid3d m = Rigid3d::Interpolate(a, b, 0.5);
  EXPECT_NEAR(AngleBetween(a.rotation(), m.rotation()), 0.5, 1e-12);
  EXPECT_TRUE((m.translation() - Eigen::Vector3d(1, 0, 0)).isZero(1e-12));
  EXPECT_NEAR(Difference(Rigid3d::Interpolate(a, b, 1.0), b).rotation_rad, 0.0, 1e-9);
}

TEST(SO3, ExpLogAndAngle) {
  const Eigen::Vector3d w(0.1, -0.4, 0.7);
  EXPECT_TRUE((LogSO3(ExpSO3(w)) - w).isZero(1e-12));
  EXPECT_NEAR(AngleBetween(Eigen::Quaterniond::Identity(), ExpSO3(w)), w.norm(), 1e-12);
  EXPECT_TRUE((Skew(w) * Eigen::Vector3d(1, 2, 3) - w.cross(Eigen::Vector3d(1, 2, 3))).isZero());
}

}  // namespace
}  // namespace unseen
