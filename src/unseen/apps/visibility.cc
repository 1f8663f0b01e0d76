// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/apps/visibility.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "unseen/util/error.h"

namespace unseen {

namespace {

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// Unsigned angle between two non-zero vectors, radians.
double AngleBetween(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return std::abs(std::atan2(Cross(a, b), a.dot(b)));
}

// Parameters s where the line p0 + s d crosses the line through `origin` along `dir`.
void AddLineCrossing(const Eigen::Vector2d& p0, const Eigen::Vector2d& d,
                     const Eigen::Vector2d& origin, const Eigen::Vector2d& dir,
                     std::vector<double>* s) {
  const double denom = Cross(d, dir);
  if (std::abs(denom) > 1e-12) s->push_back(Cross(origin - p0, dir) / denom);
}

// Parameters s where the line p0 + s d crosses the circle.
void AddCircleCrossings(const Eigen::Vector2d& p0, const Eigen::Vector2d& d, const Column& column,
                        std::vector<double>* s) {
  const Eigen::Vector2d m = p0 - column.centre_m;
  const double a = d.squaredNorm(), b = 2.0 * m.dot(d);
  const double c = m.squaredNorm() - column.radius_m * column.radius_m;
  const double disc = b * b - 4.0 * a * c;
  if (a <= 0.0 || disc < 0.0) return;
  s->push_back((-b - std::sqrt(disc)) / (2.0 * a));
  s->push_back((-b + std::sqrt(disc)) / (2.0 * a));
}

// Whether the sight line from `eye` to `p` passes through the column.
bool Hidden(const Eigen::Vector2d& eye, const Eigen::Vector2d& p, const Column& column) {
  const Eigen::Vector2d d = p - eye;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((column.centre_m - eye).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (eye + t * d - column.centre_m).norm() < column.radius_m;
}

}  // namespace

Eigen::Vector2d HeadingDirection(double heading_rad) {
  return {std::sin(heading_rad), std::cos(heading_rad)};
}

void VisibilityOptions::Check() const {
  UNSEEN_CHECK(area_weight >= 0 && distance_weight >= 0 && angle_weight >= 0 &&
                   area_weight + distance_weight + angle_weight > 0,
               "visibility: the weights (area {}, distance {}, angle {}) must be >= 0 with a "
               "positive sum",
               area_weight, distance_weight, angle_weight);
  UNSEEN_CHECK(max_distance_m > 0, "visibility: max_distance_m must be > 0, not {}",
               max_distance_m);
  UNSEEN_CHECK(max_angle_rad > 0 && max_angle_rad <= std::numbers::pi,
               "visibility: max_angle_rad must be in (0, pi], not {}", max_angle_rad);
}

std::optional<std::array<Eigen::Vector2d, 2>> TangentPoints(const BoundingEllipse& ellipse,
                                                            const Eigen::Vector2d& from) {
  // Object axes in the top view: x = (cos h, -sin h), z = (sin h, cos h).
  const Eigen::Vector2d ax(std::cos(ellipse.heading_rad), -std::sin(ellipse.heading_rad));
  const Eigen::Vector2d az = HeadingDirection(ellipse.heading_rad);
  const Eigen::Vector2d rel = from - ellipse.centre_m;
  const Eigen::Vector2d q(rel.dot(ax) / ellipse.semi_axes_m.x(),
                          rel.dot(az) / ellipse.semi_axes_m.y());  // unit-circle frame
  const double q2 = q.squaredNorm();
  if (q2 <= 1.0) return std::nullopt;
  const Eigen::Vector2d perp(-q.y(), q.x());
  const double h = std::sqrt(q2 - 1.0);
  std::array<Eigen::Vector2d, 2> t;
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector2d u = (q + (k == 0 ? -h : h) * perp) / q2;
    t[k] = ellipse.centre_m + u.x() * ellipse.semi_axes_m.x() * ax +
           u.y() * ellipse.semi_axes_m.y() * az;
  }
  return t;
}

VisibilityTerms Visibility(const TopViewCamera& camera, const BoundingEllipse& ellipse,
                           std::span<const Column> columns, const VisibilityOptions& options) {
  VisibilityTerms v;
  const Eigen::Vector2d eye = camera.position_m;
  const Eigen::Vector2d axis = HeadingDirection(camera.heading_rad);
  const double half_fov = 0.5 * camera.horizontal_fov_rad;

  // Area: the visible share of t1-t2 (the sum of L_i over |t1 - t2|).
  const auto tangents = TangentPoints(ellipse, eye);
  const bool inside_column = std::any_of(columns.begin(), columns.end(), [&](const Column& c) {
    return (eye - c.centre_m).norm() <= c.radius_m;
  });
  if (tangents && !inside_column) {
    const Eigen::Vector2d p0 = (*tangents)[0], d = (*tangents)[1] - p0;
    std::vector<double> cuts = {0.0, 1.0};
    AddLineCrossing(p0, d, eye, HeadingDirection(camera.heading_rad - half_fov), &cuts);
    AddLineCrossing(p0, d, eye, HeadingDirection(camera.heading_rad + half_fov), &cuts);
    for (const Column& c : columns) {
      AddCircleCrossings(p0, d, c, &cuts);
      // The lines from the eye touching the column bound its shadow.
      const Eigen::Vector2d to_eye = eye - c.centre_m;
      const double dist = to_eye.norm();
      const double along = c.radius_m / dist, across = std::sqrt(1.0 - along * along);
      const Eigen::Vector2d u = to_eye / dist, perp(-u.y(), u.x());
      for (double sign : {-1.0, 1.0}) {
        const Eigen::Vector2d touch = c.centre_m + c.radius_m * (along * u + sign * across * perp);
        AddLineCrossing(p0, d, eye, touch - eye, &cuts);
      }
    }
    std::sort(cuts.begin(), cuts.end());
    double visible = 0.0;
    bool last_visible = false;
    for (size_t i = 0; i + 1 < cuts.size(); ++i) {
      const double a = std::max(cuts[i], 0.0), b = std::min(cuts[i + 1], 1.0);
      if (b - a <= 1e-12) continue;
      const Eigen::Vector2d mid = p0 + 0.5 * (a + b) * d;
      const bool seen = AngleBetween(axis, mid - eye) <= half_fov &&
                        std::none_of(columns.begin(), columns.end(),
                                     [&](const Column& c) { return Hidden(eye, mid, c); });
      if (seen) {
        visible += b - a;
        if (!last_visible) ++v.visible_pieces;
      }
      last_visible = seen;
    }
    v.area = std::clamp(visible, 0.0, 1.0);
  }

  // Distance: how far the object's centre is from the point in focus.
  const Eigen::Vector2d focus = eye + camera.focus_distance_m * axis;
  v.distance = std::max(0.0, 1.0 - (focus - ellipse.centre_m).norm() / options.max_distance_m);
  // Angle: between the optical axis and the line camera -> object centre.
  const Eigen::Vector2d to_obj = ellipse.centre_m - eye;
  const double phi = to_obj.norm() > 0 ? AngleBetween(axis, to_obj) : 0.0;
  v.angle = std::max(0.0, 1.0 - phi / options.max_angle_rad);

  v.value = (options.area_weight * v.area + options.distance_weight * v.distance +
             options.angle_weight * v.angle) /
            (options.area_weight + options.distance_weight + options.angle_weight);
  return v;
}

}  // namespace unseen
