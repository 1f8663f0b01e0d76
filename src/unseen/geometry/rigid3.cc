// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/geometry/rigid3.h"

#include <cmath>

#include <fmt/format.h>

#include "unseen/util/error.h"

namespace unseen {

Eigen::Matrix3d Skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d s;
  s << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return s;
}

Eigen::Quaterniond ExpSO3(const Eigen::Vector3d& w) {
  const double theta = w.norm();
  const double half = 0.5 * theta;
  // sin(theta/2)/theta, with its Taylor series near zero.
  const double k = theta < 1e-8 ? 0.5 - theta * theta / 48.0 : std::sin(half) / theta;
  Eigen::Quaterniond q(std::cos(half), k * w.x(), k * w.y(), k * w.z());
  q.normalize();
  return q;
}

Eigen::Vector3d LogSO3(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0.0) q.coeffs() *= -1.0;  // angle in [0, pi]
  const double sin_half = q.vec().norm();
  if (sin_half < 1e-10) return 2.0 * q.vec() / q.w();
  const double theta = 2.0 * std::atan2(sin_half, q.w());
  return (theta / sin_half) * q.vec();
}

double AngleBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return LogSO3(a.conjugate() * b).norm();
}

Rigid3d::Rigid3d(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation)
    : translation_(translation) {
  set_rotation(rotation);
}

void Rigid3d::set_rotation(const Eigen::Quaterniond& q) {
  const double n = q.norm();
  UNSEEN_CHECK(std::isfinite(n) && n > 1e-12,
               "rotation quaternion [{} {} {} {}] is zero or not finite", q.x(), q.y(),
               q.z(), q.w());
  rotation_ = Eigen::Quaterniond(q.coeffs() / n);
}

Rigid3d Rigid3d::FromRotationMatrix(const Eigen::Matrix3d& r, const Eigen::Vector3d& t,
                                    const std::string& what, double tolerance) {
  UNSEEN_CHECK(r.allFinite() && t.allFinite(), "{}: rotation or translation is not finite",
               what);
  const double orth = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  UNSEEN_CHECK(orth <= tolerance,
               "{}: rotation matrix is not orthonormal (|R^T R - I| = {:.3g} > {:.3g})", what,
               orth, tolerance);
  const double det = r.determinant();
  UNSEEN_CHECK(det > 0.0, "{}: rotation matrix has determinant {:.6f} (a reflection)", what,
               det);
  return Rigid3d(Eigen::Quaterniond(r), t);
}

Rigid3d Rigid3d::FromMatrix(const Eigen::Matrix4d& m, const std::string& what,
                            double tolerance) {
  const Eigen::RowVector4d last = m.row(3);
  UNSEEN_CHECK((last - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() <= tolerance,
               "{}: last row of the 4x4 matrix is [{} {} {} {}], expected [0 0 0 1]", what,
               last(0), last(1), last(2), last(3));
  return FromRotationMatrix(m.topLeftCorner<3, 3>(), m.topRightCorner<3, 1>(), what,
                            tolerance);
}

namespace {

// V(w) = I + (1-cos θ)/θ² [w]x + (θ - sin θ)/θ³ [w]x², the SE(3) left Jacobian of SO(3).
Eigen::Matrix3d LeftJacobianSO3(const Eigen::Vector3d& w) {
  const double theta2 = w.squaredNorm();
  const double theta = std::sqrt(theta2);
  const Eigen::Matrix3d s = Skew(w);
  double a, b;
  if (theta < 1e-5) {
    a = 0.5 - theta2 / 24.0;
    b = 1.0 / 6.0 - theta2 / 120.0;
  } else {
    a = (1.0 - std::cos(theta)) / theta2;
    b = (theta - std::sin(theta)) / (theta2 * theta);
  }
  return Eigen::Matrix3d::Identity() + a * s + b * s * s;
}

}  // namespace

Rigid3d Rigid3d::Exp(const Vector6d& twist) {
  const Eigen::Vector3d v = twist.head<3>();
  const Eigen::Vector3d w = twist.tail<3>();
  return Rigid3d(ExpSO3(w), LeftJacobianSO3(w) * v);
}

Vector6d Rigid3d::Log() const {
  const Eigen::Vector3d w = LogSO3(rotation_);
  Vector6d twist;
  twist.head<3>() = LeftJacobianSO3(w).inverse() * translation_;
  twist.tail<3>() = w;
  return twist;
}

Eigen::Matrix4d Rigid3d::ToMatrix() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = RotationMatrix();
  m.topRightCorner<3, 1>() = translation_;
  return m;
}

Eigen::Matrix<double, 3, 4> Rigid3d::ToMatrix3x4() const { return ToMatrix().topRows<3>(); }

Rigid3d Rigid3d::Inverse() const {
  Rigid3d inv;
  inv.rotation_ = rotation_.conjugate();
  inv.translation_ = -(inv.rotation_ * translation_);
  return inv;
}

Rigid3d Rigid3d::operator*(const Rigid3d& other) const {
  Rigid3d out;
  out.rotation_ = (rotation_ * other.rotation_).normalized();
  out.translation_ = rotation_ * other.translation_ + translation_;
  return out;
}

bool Rigid3d::IsValid() const {
  return rotation_.coeffs().allFinite() && translation_.allFinite() &&
         std::abs(rotation_.norm() - 1.0) < 1e-6;
}

Rigid3d Rigid3d::Interpolate(const Rigid3d& a, const Rigid3d& b, double t) {
  return Rigid3d(a.rotation_.slerp(t, b.rotation_),
                 (1.0 - t) * a.translation_ + t * b.translation_);
}

std::string Rigid3d::ToString() const {
  return fmt::format("t=[{:.6f} {:.6f} {:.6f}] q=[{:.6f} {:.6f} {:.6f} {:.6f}]",
                     translation_.x(), translation_.y(), translation_.z(), rotation_.x(),
                     rotation_.y(), rotation_.z(), rotation_.w());
}

PoseDifference Difference(const Rigid3d& a, const Rigid3d& b) {
  return {(a.translation() - b.translation()).norm(), AngleBetween(a.rotation(), b.rotation())};
}

}  // namespace unseen
