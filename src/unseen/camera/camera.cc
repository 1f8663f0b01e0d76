// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/camera/camera.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "unseen/util/error.h"

namespace unseen {

PixelRect PixelRect::Intersect(const PixelRect& o) const {
  PixelRect r{std::max(x0, o.x0), std::max(y0, o.y0), std::min(x1, o.x1), std::min(y1, o.y1)};
  if (r.empty()) return {};
  return r;
}

PinholeCamera PinholeCamera::Centered(int width, int height, double focal_px) {
  PinholeCamera c;
  c.width = width;
  c.height = height;
  c.fx = c.fy = focal_px;
  c.cx = 0.5 * (width - 1);
  c.cy = 0.5 * (height - 1);
  return c;
}

void PinholeCamera::Check(const std::string& what) const {
  UNSEEN_CHECK(width > 0 && height > 0, "{}: image size {}x{} must be positive", what, width,
               height);
  UNSEEN_CHECK(std::isfinite(fx) && std::isfinite(fy) && fx > 0.0 && fy > 0.0,
               "{}: focal lengths fx={} fy={} must be positive and finite", what, fx, fy);
  UNSEEN_CHECK(std::isfinite(cx) && std::isfinite(cy),
               "{}: principal point cx={} cy={} must be finite", what, cx, cy);
  const size_t n = distortion.size();
  UNSEEN_CHECK(n == 0 || n == 4 || n == 5 || n == 8 || n == 12 || n == 14,
               "{}: distortion has {} coefficients; OpenCV takes 4, 5, 8, 12 or 14", what, n);
  for (double d : distortion) {
    UNSEEN_CHECK(std::isfinite(d), "{}: distortion coefficient {} is not finite", what, d);
  }
}

Eigen::Matrix3d PinholeCamera::K() const {
  Eigen::Matrix3d k;
  k << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
  return k;
}

bool PinholeCamera::HasDistortion() const {
  return std::any_of(distortion.begin(), distortion.end(), [](double d) { return d != 0.0; });
}

Eigen::Vector2d PinholeCamera::Project(const Eigen::Vector3d& p) const {
  if (!(p.z() > 0.0)) {
    return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  }
  return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy};
}

Eigen::Vector3d PinholeCamera::Unproject(const Eigen::Vector2d& q, double z) const {
  return {(q.x() - cx) / fx * z, (q.y() - cy) / fy * z, z};
}

bool PinholeCamera::InImage(const Eigen::Vector2d& q) const {
  return q.x() >= -0.5 && q.y() >= -0.5 && q.x() < width - 0.5 && q.y() < height - 0.5;
}

PinholeCamera PinholeCamera::Scaled(double s) const {
  UNSEEN_CHECK(s > 0.0 && std::isfinite(s), "camera scale factor {} must be positive", s);
  PinholeCamera c = *this;
  c.width = static_cast<int>(std::ceil(width / s));
  c.height = static_cast<int>(std::ceil(height / s));
  c.fx = fx / s;
  c.fy = fy / s;
  c.cx = (cx + 0.5) / s - 0.5;
  c.cy = (cy + 0.5) / s - 0.5;
  return c;
}

PinholeCamera PinholeCamera::PyramidLevel(int level) const {
  UNSEEN_CHECK(level >= 0 && level < 16, "pyramid level {} out of range [0, 15]", level);
  return Scaled(static_cast<double>(1 << level));
}

namespace {

// The pixels whose centres lie within [xl, xh] x [yl, yh] (image coordinates), clipped to
// a width x height image; std::nullopt when none.
std::optional<PixelRect> PixelsSpanned(double xl, double xh, double yl, double yh, int width,
                                       int height) {
  auto clamp_lo = [](double v, int size) {
    return static_cast<int>(std::clamp(std::floor(v + 0.5), 0.0, double(size)));
  };
  auto clamp_hi = [](double v, int size) {
    return static_cast<int>(std::clamp(std::ceil(v + 0.5), 0.0, double(size)));
  };
  PixelRect rect{clamp_lo(xl, width), clamp_lo(yl, height), clamp_hi(xh, width),
                 clamp_hi(yh, height)};
  if (rect.empty()) return std::nullopt;
  return rect;
}

}  // namespace

std::optional<PixelRect> PinholeCamera::SphereRect(const Eigen::Vector3d& p, double r) const {
  if (!p.allFinite() || !(r >= 0.0)) return std::nullopt;
  if (p.norm() <= r) return ImageRect();
  if (p.z() <= -r) return std::nullopt;  // entirely behind the camera
  // Per axis a: psi = atan(p_a / p_z), theta = asin(r / sqrt(p_a^2 + p_z^2)), edges at
  // f_a * tan(psi +- theta) + c_a (4.16)-(4.21). Angles are measured from the optical axis.
  auto edges = [&](double pa, double f, double c, int size, double* lo, double* hi) {
    const double dist = std::hypot(pa, p.z());
    if (r >= dist) {  // the sphere spans the whole axis
      *lo = -0.5;
      *hi = size - 0.5;
      return;
    }
    const double psi = std::atan2(pa, p.z());
    const double theta = std::asin(r / dist);
    const double a0 = psi - theta, a1 = psi + theta;
    constexpr double kHalfPi = M_PI / 2;
    *lo = a0 <= -kHalfPi ? -std::numeric_limits<double>::infinity() : f * std::tan(a0) + c;
    *hi = a1 >= kHalfPi ? std::numeric_limits<double>::infinity() : f * std::tan(a1) + c;
  };
  double xl, xh, yl, yh;
  edges(p.x(), fx, cx, width, &xl, &xh);
  edges(p.y(), fy, cy, height, &yl, &yh);
  return PixelsSpanned(xl, xh, yl, yh, width, height);
}

int Rig::Find(const std::string& name) const {
  for (int i = 0; i < size(); ++i) {
    if (cameras[i].name == name) return i;
  }
  return -1;
}

void Rig::Check() const {
  UNSEEN_CHECK(!cameras.empty(), "rig has no cameras");
  for (const RigCamera& c : cameras) {
    c.intrinsics.Check("camera '" + c.name + "'");
    UNSEEN_CHECK(c.world_from_cam.IsValid(), "camera '{}': world_from_cam is not a valid pose",
                 c.name);
  }
}

std::optional<PinholeCamera::Bounds> PinholeCamera::ProjectedBounds(
    std::span<const Eigen::Vector3d> points_in_cam) const {
  if (points_in_cam.empty()) return std::nullopt;
  Bounds b{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
           std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (const Eigen::Vector3d& p : points_in_cam) {
    if (!p.allFinite() || !(p.z() >= 1e-3)) return std::nullopt;
    const double x = fx * p.x() / p.z() + cx, y = fy * p.y() / p.z() + cy;
    b.x_min = std::min(b.x_min, x);
    b.x_max = std::max(b.x_max, x);
    b.y_min = std::min(b.y_min, y);
    b.y_max = std::max(b.y_max, y);
  }
  return b;
}

std::optional<PixelRect> PinholeCamera::PointsRect(
    std::span<const Eigen::Vector3d> points_in_cam) const {
  const std::optional<Bounds> b = ProjectedBounds(points_in_cam);
  if (!b) return std::nullopt;
  return PixelsSpanned(b->x_min, b->x_max, b->y_min, b->y_max, width, height);
}

}  // namespace unseen
