// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Rigid transforms. A `Rigid3d` named `target_from_source` maps coordinates of a
// point in frame `source` to frame `target`:  p_in_target = target_from_source * p_in_source,
// so that `cam_from_obj = cam_from_world * world_from_obj` reads right. Units: metres.
#pragma once

#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace unseen {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

// [w]x, the cross-product matrix: Skew(w) * v == w.cross(v).
Eigen::Matrix3d Skew(const Eigen::Vector3d& w);

// Rodrigues: the rotation by |w| radians about w/|w| (exact for small |w|).
Eigen::Quaterniond ExpSO3(const Eigen::Vector3d& w);
// Inverse of ExpSO3, the rotation vector with angle in [0, pi].
Eigen::Vector3d LogSO3(const Eigen::Quaterniond& q);
// Angle in radians of the rotation taking `a` to `b`, in [0, pi].
double AngleBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b);

class Rigid3d {
 public:
  Rigid3d() = default;
  // `rotation` is normalised; it must be finite and non-zero.
  Rigid3d(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation);

  // From a rotation matrix and translation. Throws unseen::Error naming `what` when the
  // matrix is not a rotation (non-orthonormal beyond `tolerance`, det != +1) or has NaN.
  static Rigid3d FromRotationMatrix(const Eigen::Matrix3d& rotation,
                                    const Eigen::Vector3d& translation,
                                    const std::string& what = "pose",
                                    double tolerance = 1e-4);
  // From a 4x4 homogeneous matrix (last row must be 0 0 0 1); same checks.
  static Rigid3d FromMatrix(const Eigen::Matrix4d& matrix, const std::string& what = "pose",
                            double tolerance = 1e-4);

  // SE(3) exponential of the twist [v; w] (v translational, w rotational, body-fixed
  // left-Jacobian convention: Exp(x).translation() = V(w) v).
  static Rigid3d Exp(const Vector6d& twist);
  // Inverse of Exp.
  Vector6d Log() const;

  const Eigen::Quaterniond& rotation() const { return rotation_; }
  const Eigen::Vector3d& translation() const { return translation_; }
  Eigen::Matrix3d RotationMatrix() const { return rotation_.toRotationMatrix(); }
  Eigen::Matrix4d ToMatrix() const;
  // Same as ToMatrix but 3x4 [R | t].
  Eigen::Matrix<double, 3, 4> ToMatrix3x4() const;

  void set_translation(const Eigen::Vector3d& t) { translation_ = t; }
  void set_rotation(const Eigen::Quaterniond& q);

  Rigid3d Inverse() const;
  Rigid3d operator*(const Rigid3d& other) const;
  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const {
    return rotation_ * p + translation_;
  }

  // True when every entry is finite and the quaternion has unit norm.
  bool IsValid() const;

  // Geodesic interpolation: slerp of rotation, linear in translation; t in [0, 1].
  static Rigid3d Interpolate(const Rigid3d& a, const Rigid3d& b, double t);

  // "t=[x y z] q=[x y z w]" for logs.
  std::string ToString() const;

 private:
  Eigen::Quaterniond rotation_ = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation_ = Eigen::Vector3d::Zero();
};

// Rotation (rad) and translation (same unit as poses) difference between two poses.
struct PoseDifference {
  double translation = 0.0;
  double rotation_rad = 0.0;
};
PoseDifference Difference(const Rigid3d& a, const Rigid3d& b);

}  // namespace unseen
