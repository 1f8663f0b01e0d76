// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/motion_predictor.h"

#include <cmath>

#include "unseen/util/error.h"

namespace unseen {

const char* ToString(PredictorType type) {
  switch (type) {
    case PredictorType::kConstantVelocityKalman: return "kalman";
    case PredictorType::kHold: return "none";
  }
  return "?";
}

PredictorType ParsePredictorType(const std::string& text, const std::string& what) {
  if (text == "kalman") return PredictorType::kConstantVelocityKalman;
  if (text == "none" || text == "hold") return PredictorType::kHold;
  ThrowError("{}: unknown predictor '{}' (kalman, none)", what, text);
}

void MotionPredictorOptions::Check() const {
  for (auto [name, value] : {std::pair{"linear_accel_sigma", linear_accel_sigma},
                             std::pair{"angular_accel_sigma", angular_accel_sigma},
                             std::pair{"position_sigma", position_sigma},
                             std::pair{"rotation_sigma", rotation_sigma}}) {
    UNSEEN_CHECK(value > 0.0 && std::isfinite(value), "predictor.{} {} must be > 0", name, value);
  }
  UNSEEN_CHECK(min_confidence > 0.0 && min_confidence <= 1.0,
               "predictor.min_confidence {} must be in (0, 1]", min_confidence);
  UNSEEN_CHECK(confidence_power >= 0.0 && confidence_power <= 16.0,
               "predictor.confidence_power {} must be in [0, 16]", confidence_power);
}

ConstantVelocityKalmanPredictor::ConstantVelocityKalmanPredictor(
    const MotionPredictorOptions& options)
    : options_(options) {
  options_.Check();
  Reset(Rigid3d());
}

void ConstantVelocityKalmanPredictor::Reset(const Rigid3d& world_from_obj) {
  reference_ = world_from_obj.rotation();
  for (int i = 0; i < 6; ++i) {
    Axis& a = axes_[i];
    const double sigma = i < 3 ? options_.position_sigma : options_.rotation_sigma;
    a.x = i < 3 ? world_from_obj.translation()(i) : 0.0;
    a.v = 0.0;
    a.pxx = sigma * sigma;
    a.pxv = 0.0;
    a.pvv = 0.0;  // at rest until told otherwise
  }
}

Rigid3d ConstantVelocityKalmanPredictor::Predict(double dt) {
  UNSEEN_CHECK(dt > 0.0 && std::isfinite(dt), "MotionPredictor::Predict: dt {} s must be > 0", dt);
  for (int i = 0; i < 6; ++i) {
    Axis& a = axes_[i];
    const double q = i < 3 ? options_.linear_accel_sigma : options_.angular_accel_sigma;
    const double q2 = q * q;
    // x' = x + v dt;  P' = F P F^T + Q, Q of a white-acceleration model.
    a.x += a.v * dt;
    const double pxx = a.pxx + 2 * dt * a.pxv + dt * dt * a.pvv + q2 * dt * dt * dt / 3;
    const double pxv = a.pxv + dt * a.pvv + q2 * dt * dt / 2;
    const double pvv = a.pvv + q2 * dt;
    a.pxx = pxx;
    a.pxv = pxv;
    a.pvv = pvv;
  }
  return Pose();
}

void ConstantVelocityKalmanPredictor::Correct(const Rigid3d& world_from_obj, double confidence) {
  UNSEEN_CHECK(world_from_obj.IsValid(), "MotionPredictor::Correct: invalid pose {}",
               world_from_obj.ToString());
  UNSEEN_CHECK(confidence >= 0.0 && confidence <= 1.0,
               "MotionPredictor::Correct: confidence {} not in [0, 1]", confidence);
  if (confidence < options_.min_confidence) return;
  const double noise_gain = std::pow(confidence, -options_.confidence_power);  // R / c^p
  const Eigen::Vector3d rot = LogSO3(world_from_obj.rotation() * reference_.inverse());
  for (int i = 0; i < 6; ++i) {
    Axis& a = axes_[i];
    const double sigma = i < 3 ? options_.position_sigma : options_.rotation_sigma;
    const double z = i < 3 ? world_from_obj.translation()(i) : rot(i - 3);
    const double s = a.pxx + noise_gain * sigma * sigma;
    const double kx = a.pxx / s, kv = a.pxv / s;
    const double innovation = z - a.x;
    a.x += kx * innovation;
    a.v += kv * innovation;
    const double pxx = (1 - kx) * a.pxx;
    const double pxv = (1 - kx) * a.pxv;
    const double pvv = a.pvv - kv * a.pxv;
    a.pxx = pxx;
    a.pxv = pxv;
    a.pvv = pvv;
  }
  // Re-base the rotation state on the corrected rotation (keeps the vector small).
  const Eigen::Vector3d r(axes_[3].x, axes_[4].x, axes_[5].x);
  reference_ = (ExpSO3(r) * reference_).normalized();
  for (int i = 3; i < 6; ++i) axes_[i].x = 0.0;
}

Vector6d ConstantVelocityKalmanPredictor::Velocity() const {
  Vector6d v;
  for (int i = 0; i < 6; ++i) v(i) = axes_[i].v;
  return v;
}

Rigid3d ConstantVelocityKalmanPredictor::Pose() const {
  const Eigen::Vector3d r(axes_[3].x, axes_[4].x, axes_[5].x);
  return Rigid3d(ExpSO3(r) * reference_, Eigen::Vector3d(axes_[0].x, axes_[1].x, axes_[2].x));
}

std::unique_ptr<MotionPredictor> MakeMotionPredictor(const MotionPredictorOptions& options) {
  options.Check();
  switch (options.type) {
    case PredictorType::kConstantVelocityKalman:
      return std::make_unique<ConstantVelocityKalmanPredictor>(options);
    case PredictorType::kHold:
      return std::make_unique<HoldPredictor>(options.min_confidence);
  }
  ThrowError("unknown predictor type");
}

}  // namespace unseen
