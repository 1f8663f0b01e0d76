// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The visibility measure of dynamic camera reconfiguration (SPEC 7.2, thesis 5.3.1, (5.1)),
// computed in the top view as the thesis did: the ground plane seen from above, columns as
// circles, the object as an ellipse bounding its footprint, cameras with a horizontal field
// of view. Top-view points are the world's (x, z) in metres (x right, z away from the
// tracking rig); a heading is a yaw about the world's vertical y axis (down), 0 looking
// along +z and pi/2 along +x, so that the direction of heading h is (sin h, cos h).
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <span>

namespace unseen {

// The top-view direction (sin h, cos h) of heading `heading_rad`.
Eigen::Vector2d HeadingDirection(double heading_rad);

// A vertical column obstacle: a circle in the top view.
struct Column {
  Eigen::Vector2d centre_m = Eigen::Vector2d::Zero();
  double radius_m = 0.05;
};

// An ellipse bounding the object's footprint: semi-axes along the object's x and z axes,
// which are turned by the object's yaw `heading_rad` (its z axis points along
// HeadingDirection(heading_rad)).
struct BoundingEllipse {
  Eigen::Vector2d centre_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d semi_axes_m = Eigen::Vector2d::Constant(0.068);  // (along x, along z)
  double heading_rad = 0.0;
};

// A camera in the top view: its optical (and rotation) centre, the heading of its optical
// axis, its horizontal field of view and the distance at which it is focused.
struct TopViewCamera {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  double heading_rad = 0.0;
  double horizontal_fov_rad = 0.4189;  // 24 deg, the thesis's reconfigurable cameras
  double focus_distance_m = 0.9;       // f = position + focus_distance * axis, (5.1)
};

struct VisibilityOptions {
  // W_area, W_dist, W_angle of (5.1): weights of the visible-area, distance and angle terms.
  double area_weight = 1.0;
  double distance_weight = 1.0;
  double angle_weight = 1.0;
  double max_distance_m = 1.5;    // d_max, (5.1): farthest object from the focal point, m
  double max_angle_rad = 0.2094;  // phi_max, (5.1): 12 deg, half the 24 deg field of view
  void Check() const;
};

// The terms of (5.1), each in [0, 1], and their weighted mean.
struct VisibilityTerms {
  double area = 0.0;       // visible share of the tangent-point segment t1-t2
  double distance = 0.0;   // 1 - |f - c_obj| / d_max, clamped at 0
  double angle = 0.0;      // 1 - phi / phi_max, clamped at 0
  double value = 0.0;      // V, (5.1)
  int visible_pieces = 0;  // n_area: distinct visible parts of t1-t2
};

// The points t1, t2 where the lines from `from` touch `ellipse` (tangency is kept by the
// affine map to the unit circle). std::nullopt when `from` is inside the ellipse.
std::optional<std::array<Eigen::Vector2d, 2>> TangentPoints(const BoundingEllipse& ellipse,
                                                            const Eigen::Vector2d& from);

// The visibility (5.1) of the object bounded by `ellipse` to `camera` among `columns`. The
// area term is the share of segment t1-t2 inside the field of view and not hidden by a
// column (the segment is split where a field-of-view edge, a column or a line from the
// camera touching a column crosses it; each piece is judged at its middle). A camera inside
// the ellipse or a column sees nothing of the object's area.
VisibilityTerms Visibility(const TopViewCamera& camera, const BoundingEllipse& ellipse,
                           std::span<const Column> columns, const VisibilityOptions& options);

}  // namespace unseen
