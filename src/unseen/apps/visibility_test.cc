// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/apps/visibility.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "unseen/util/error.h"

namespace unseen {
namespace {

// A camera at the origin looking along +z at a round object 1 m ahead, in focus.
struct Scene {
  TopViewCamera camera;
  BoundingEllipse object;
  VisibilityOptions options;
  Scene() {
    camera.focus_distance_m = 1.0;
    object.centre_m = {0.0, 1.0};
    object.semi_axes_m = {0.05, 0.05};
  }
  VisibilityTerms Score(const std::vector<Column>& columns = {}) const {
    return Visibility(camera, object, columns, options);
  }
};

TEST(Visibility, CentredUnoccludedObjectScoresOne) {
  const VisibilityTerms v = Scene().Score();
  EXPECT_NEAR(v.area, 1.0, 1e-12);
  EXPECT_NEAR(v.distance, 1.0, 1e-12);
  EXPECT_NEAR(v.angle, 1.0, 1e-12);
  EXPECT_NEAR(v.value, 1.0, 1e-12);
  EXPECT_EQ(v.visible_pieces, 1);
}

TEST(Visibility, OccludedOrOffAxisObjectScoresLower) {
  Scene scene;
  const double centred = scene.Score().value;
  const VisibilityTerms occluded = scene.Score({Column{{0.0, 0.5}, 0.05}});
  EXPECT_LT(occluded.value, centred - 0.3);
  Scene off_axis;
  off_axis.camera.heading_rad = 0.15;  // the object 8.6 deg off the axis, still in view
  const VisibilityTerms off = off_axis.Score();
  EXPECT_NEAR(off.area, 1.0, 1e-12);
  EXPECT_NEAR(off.angle, 1.0 - 0.15 / off_axis.options.max_angle_rad, 1e-9);
  EXPECT_LT(off.value, centred - 0.1);
}

TEST(Visibility, ObjectFullyBehindAColumnHasNoArea) {
  Scene scene;
  const VisibilityTerms v = scene.Score({Column{{0.0, 0.5}, 0.05}});
  EXPECT_EQ(v.area, 0.0);
  EXPECT_EQ(v.visible_pieces, 0);
  // Distance and angle do not see columns: the object is still in focus and centred.
  EXPECT_NEAR(v.value, 2.0 / 3.0, 1e-12);
}

TEST(Visibility, ThinColumnSplitsTheSegmentInTwo) {
  Scene scene;
  // Seen from the camera the column at 0.5 m spans +-asin(0.01 / 0.5) = +-0.02 rad, the
  // object's tangent segment (at 0.9975 m) +-0.0499 m: 2 * 0.9975 tan(0.02) / 0.0999 = 40 %
  // of it is hidden, in the middle.
  const VisibilityTerms v = scene.Score({Column{{0.0, 0.5}, 0.01}});
  EXPECT_EQ(v.visible_pieces, 2);
  EXPECT_NEAR(v.area, 0.6005, 0.001);
  // A column behind the object hides nothing.
  EXPECT_NEAR(scene.Score({Column{{0.0, 1.5}, 0.2}}).area, 1.0, 1e-12);
}

TEST(Visibility, FieldOfViewEdgeThroughTheCentreShowsHalf) {
  Scene scene;
  scene.camera.heading_rad = 0.5 * scene.camera.horizontal_fov_rad;
  EXPECT_NEAR(scene.Score().area, 0.5, 1e-9);
  scene.camera.heading_rad = 3.0 * scene.camera.horizontal_fov_rad;
  const VisibilityTerms out = scene.Score();
  EXPECT_EQ(out.area, 0.0);
  EXPECT_EQ(out.angle, 0.0);  // beyond phi_max
}

TEST(Visibility, DistanceTermFallsWithDistanceFromTheFocus) {
  Scene scene;
  scene.object.centre_m = {0.0, 1.3};
  EXPECT_NEAR(scene.Score().distance, 1.0 - 0.3 / scene.options.max_distance_m, 1e-12);
  scene.object.centre_m = {0.0, 1.0 + 2.0 * scene.options.max_distance_m};
  EXPECT_EQ(scene.Score().distance, 0.0);
}

TEST(Visibility, WeightsNormalise) {
  Scene scene;
  scene.camera.heading_rad = 0.1;
  const std::vector<Column> columns = {{{0.02, 0.6}, 0.01}};
  const VisibilityTerms v = scene.Score(columns);
  scene.options.area_weight = scene.options.distance_weight = scene.options.angle_weight = 3.0;
  EXPECT_NEAR(scene.Score(columns).value, v.value, 1e-12);
  EXPECT_NEAR(v.value, (v.area + v.distance + v.angle) / 3.0, 1e-12);
  scene.options.distance_weight = scene.options.angle_weight = 0.0;
  EXPECT_NEAR(scene.Score(columns).value, v.area, 1e-12);
}

TEST(Visibility, TangentPointsTouchTheEllipse) {
  BoundingEllipse e;
  e.centre_m = {0.3, 1.2};
  e.semi_axes_m = {0.12, 0.05};
  e.heading_rad = 0.7;
  const Eigen::Vector2d from(-0.4, 0.2);
  const auto t = TangentPoints(e, from);
  ASSERT_TRUE(t.has_value());
  const Eigen::Vector2d ax(std::cos(e.heading_rad), -std::sin(e.heading_rad));
  const Eigen::Vector2d az = HeadingDirection(e.heading_rad);
  for (const Eigen::Vector2d& p : *t) {
    const Eigen::Vector2d r = p - e.centre_m;
    const double u = r.dot(ax) / e.semi_axes_m.x(), w = r.dot(az) / e.semi_axes_m.y();
    EXPECT_NEAR(u * u + w * w, 1.0, 1e-9);  // on the ellipse
    const Eigen::Vector2d normal =
        ax * u / e.semi_axes_m.x() + az * w / e.semi_axes_m.y();               // gradient direction
    EXPECT_NEAR(normal.normalized().dot((p - from).normalized()), 0.0, 1e-9);  // tangent
  }
  EXPECT_GT(((*t)[0] - (*t)[1]).norm(), 0.05);
  EXPECT_FALSE(TangentPoints(e, e.centre_m).has_value());
}

TEST(Visibility, CameraInsideAColumnSeesNothing) {
  Scene scene;
  EXPECT_EQ(scene.Score({Column{{0.0, 0.0}, 0.1}}).area, 0.0);
}

TEST(VisibilityOptions, CheckRejectsNonsense) {
  VisibilityOptions o;
  EXPECT_NO_THROW(o.Check());
  o.area_weight = -1.0;
  EXPECT_THROW(o.Check(), Error);
  o = VisibilityOptions();
  o.area_weight = o.distance_weight = o.angle_weight = 0.0;
  EXPECT_THROW(o.Check(), Error);
  o = VisibilityOptions();
  o.max_distance_m = 0.0;
  EXPECT_THROW(o.Check(), Error);
}

}  // namespace
}  // namespace unseen
