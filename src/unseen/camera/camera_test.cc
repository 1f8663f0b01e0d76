// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/camera/camera.h"

#include <gtest/gtest.h>

#include "unseen/util/error.h"

namespace unseen {
namespace {

PinholeCamera ThesisCamera() { return PinholeCamera::Centered(512, 256, 837.3); }

TEST(PinholeCamera, ProjectUnprojectRoundTrip) {
  const PinholeCamera c = ThesisCamera();
  const Eigen::Vector3d p(0.05, -0.02, 1.2);
  const Eigen::Vector2d q = c.Project(p);
  EXPECT_TRUE((c.Unproject(q, 1.2) - p).isZero(1e-12));
  EXPECT_TRUE((c.Project({0, 0, 1}) - Eigen::Vector2d(255.5, 127.5)).isZero());
  EXPECT_TRUE(c.Project({0, 0, -1}).hasNaN());
}

TEST(PinholeCamera, PyramidLevelKeepsPixelCentres) {
  const PinholeCamera c = ThesisCamera();
  const PinholeCamera c1 = c.PyramidLevel(1);
  EXPECT_EQ(c1.width, 256);
  EXPECT_EQ(c1.height, 128);
  // The image centre stays the image centre.
  EXPECT_DOUBLE_EQ(c1.cx, 127.5);
  EXPECT_DOUBLE_EQ(c1.cy, 63.5);
  const Eigen::Vector3d p(0.03, 0.01, 0.9);
  // A point's level-1 pixel is its level-0 pixel mapped by (q + 0.5)/2 - 0.5.
  EXPECT_TRUE((c1.Project(p) - ((c.Project(p).array() + 0.5) / 2 - 0.5).matrix()).isZero(1e-9));
}

TEST(PinholeCamera, SphereRectContainsProjectedSphere) {
  const PinholeCamera c = ThesisCamera();
  const Eigen::Vector3d centre(0.04, -0.03, 1.0);
  const double r = 0.083;
  const auto rect = c.SphereRect(centre, r);
  ASSERT_TRUE(rect.has_value());
  // Sample the sphere surface: every projection falls inside the rectangle, and the
  // rectangle is tight (within a pixel of the extreme projections).
  double xmin = 1e9, xmax = -1e9, ymin = 1e9, ymax = -1e9;
  for (int i = 0; i < 200; ++i) {
    for (int j = 0; j < 100; ++j) {
      const double th = M_PI * j / 99.0, ph = 2 * M_PI * i / 200.0;
      const Eigen::Vector3d p =
          centre + r * Eigen::Vector3d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph),
                                       std::cos(th));
      const Eigen::Vector2d q = c.Project(p);
      xmin = std::min(xmin, q.x()); xmax = std::max(xmax, q.x());
      ymin = std::min(ymin, q.y()); ymax = std::max(ymax, q.y());
    }
  }
  EXPECT_LE(rect->x0, xmin + 0.5);
  EXPECT_GE(rect->x1, xmax + 0.5);
  EXPECT_LE(rect->y0, ymin + 0.5);
  EXPECT_GE(rect->y1, ymax + 0.5);
  EXPECT_GT(rect->x0, xmin - 2.0);
  EXPECT_LT(rect->x1, xmax + 3.0);
}

TEST(PinholeCamera, SphereRectOutsideAndBehind) {
  const PinholeCamera c = ThesisCamera();
  EXPECT_FALSE(c.SphereRect({0, 0, -2}, 0.1).has_value());
  EXPECT_FALSE(c.SphereRect({5, 0, 1}, 0.1).has_value());
  const auto all = c.SphereRect({0, 0, 0.05}, 0.1);
  ASSERT_TRUE(all.has_value());
  EXPECT_EQ(*all, c.ImageRect());
}

TEST(PinholeCamera, CheckRejectsBadIntrinsics) {
  PinholeCamera c = ThesisCamera();
  EXPECT_NO_THROW(c.Check());
  c.fx = -1;
  EXPECT_THROW(c.Check("cam0"), Error);
  c = ThesisCamera();
  c.width = 0;
  EXPECT_THROW(c.Check(), Error);
  c = ThesisCamera();
  c.distortion = {0.1, 0.2, 0.3};
  EXPECT_THROW(c.Check(), Error);
  c = ThesisCamera();
  c.cy = std::nan("");
  EXPECT_THROW(c.Check(), Error);
}

}  // namespace
}  // namespace unseen
