// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/camera/camera.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

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

TEST(PinholeCamera, PointsRectBoundsTheProjectionsTightly) {
  const PinholeCamera cam = PinholeCamera::Centered(640, 480, 500.0);
  // A 10 cm box 1 m away, turned: its corners' rectangle holds every projected point of
  // the box and is tighter than its bounding sphere's.
  const Rigid3d cam_from_obj(ExpSO3(Eigen::Vector3d(0.3, 0.5, 0.1)), Eigen::Vector3d(0.05, 0, 1));
  std::vector<Eigen::Vector3d> corners;
  for (int k = 0; k < 8; ++k) {
    corners.push_back(cam_from_obj * Eigen::Vector3d(k & 1 ? 0.05 : -0.05, k & 2 ? 0.05 : -0.05,
                                                     k & 4 ? 0.05 : -0.05));
  }
  const std::optional<PixelRect> rect = cam.PointsRect(corners);
  ASSERT_TRUE(rect.has_value());
  cv::RNG rng(2);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector3d p_in_obj(rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05),
                                   rng.uniform(-0.05, 0.05));
    const Eigen::Vector2d px = cam.Project(cam_from_obj * p_in_obj);
    const int x = static_cast<int>(std::lround(px.x())), y = static_cast<int>(std::lround(px.y()));
    EXPECT_TRUE(x >= rect->x0 && x < rect->x1 && y >= rect->y0 && y < rect->y1) << x << " " << y;
  }
  const std::optional<PixelRect> sphere =
      cam.SphereRect(cam_from_obj.translation(), 0.05 * std::sqrt(3.0));
  ASSERT_TRUE(sphere.has_value());
  EXPECT_LT(rect->width() * rect->height(), sphere->width() * sphere->height());
  EXPECT_EQ(rect->Intersect(*sphere), *rect);
  // A point behind the camera leaves the rectangle unbounded; no points, no rectangle.
  corners.push_back(Eigen::Vector3d(0, 0, -0.5));
  EXPECT_FALSE(cam.PointsRect(corners).has_value());
  EXPECT_FALSE(cam.PointsRect({}).has_value());
  // Entirely off to the side of the image.
  const std::vector<Eigen::Vector3d> aside = {Eigen::Vector3d(5, 0, 1), Eigen::Vector3d(6, 0.1, 1)};
  EXPECT_FALSE(cam.PointsRect(aside).has_value());
}

TEST(PinholeCamera, ProjectedBoundsAreNotClippedToTheImage) {
  const PinholeCamera cam = PinholeCamera::Centered(640, 480, 500.0);
  // Points off to the side: their box lies right of the image, exactly where they project.
  const std::vector<Eigen::Vector3d> aside = {Eigen::Vector3d(5, 0, 1), Eigen::Vector3d(6, 0.1, 2)};
  const std::optional<PinholeCamera::Bounds> b = cam.ProjectedBounds(aside);
  ASSERT_TRUE(b.has_value());
  EXPECT_DOUBLE_EQ(b->x_min, cam.Project(aside[1]).x());
  EXPECT_DOUBLE_EQ(b->x_max, cam.Project(aside[0]).x());
  EXPECT_DOUBLE_EQ(b->y_min, cam.Project(aside[0]).y());
  EXPECT_DOUBLE_EQ(b->y_max, cam.Project(aside[1]).y());
  EXPECT_GT(b->x_min, cam.width);
  // Behind the camera or not finite: unbounded; no points: nothing.
  EXPECT_FALSE(cam.ProjectedBounds(std::vector<Eigen::Vector3d>{{0, 0, -0.5}}).has_value());
  EXPECT_FALSE(cam.ProjectedBounds(std::vector<Eigen::Vector3d>{{std::nan(""), 0, 1}}).has_value());
  EXPECT_FALSE(cam.ProjectedBounds({}).has_value());
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
