// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Motion predictors (SPEC 3.7): predict the object's pose at the next frame from the
// poses estimated so far, and expose its velocity (for the on-line modeller). A small
// interface so that other predictors (fading memory, EKF/UKF, IMM, odometry inputs) can
// be added; the constant-velocity Kalman filter of the thesis and a "hold the last pose"
// predictor for comparison are provided.
#pragma once

#include <memory>
#include <string>

#include "unseen/geometry/rigid3.h"

namespace unseen {

class MotionPredictor {
 public:
  virtual ~MotionPredictor() = default;
  // Forgets the past: the object is at `world_from_obj` and at rest.
  virtual void Reset(const Rigid3d& world_from_obj) = 0;
  // Advances the state by `dt_s` seconds (> 0) and returns the predicted world_from_obj.
  virtual Rigid3d Predict(double dt_s) = 0;
  // Feeds the pose estimated for the frame last predicted with its confidence in [0, 1]:
  // the less confident, the less the pose moves the state (1 = a fully trusted pose).
  virtual void Correct(const Rigid3d& world_from_obj, double confidence) = 0;
  // The same for a fully trusted pose.
  void Correct(const Rigid3d& world_from_obj) { Correct(world_from_obj, 1.0); }
  // Estimated velocity of the object: (linear m/s of its origin, angular rad/s), world frame.
  virtual Vector6d Velocity() const = 0;
  // The current (corrected or predicted) pose estimate.
  virtual Rigid3d Pose() const = 0;
};

enum class PredictorType { kConstantVelocityKalman, kHold };
const char* ToString(PredictorType type);  // "kalman", "none"
PredictorType ParsePredictorType(const std::string& text, const std::string& what = "predictor");

struct MotionPredictorOptions {
  PredictorType type = PredictorType::kConstantVelocityKalman;
  // Process noise: white acceleration spectral densities of the constant-velocity model.
  double linear_accel_sigma = 2.0;   // m/s^2
  double angular_accel_sigma = 10.0; // rad/s^2
  // Measurement noise of the tracked pose.
  double position_sigma = 0.002;     // m
  double rotation_sigma = 0.01;      // rad
  // A pose of confidence c in [min_confidence, 1] corrects the state with its measurement
  // variance grown to R / c^confidence_power; a less confident pose does not correct it
  // at all (the filter coasts), so that a doubtful solve (an occluder, a drifting depth)
  // does not teach it a velocity that carries the next frames away. With the sigmas above
  // the prior is much wider than R, so only a high power weighs much: with power 4 the gain
  // on position drops from 0.97 at c = 1 to about 0.65 at c = 0.5. On the occlusion
  // sequences powers 1, 2 and 4 tracked no better than the plain floor (0), which is the
  // default.
  double min_confidence = 0.5;
  double confidence_power = 0.0;
  void Check() const;
};

// Constant-velocity Kalman filter on position and on the rotation vector relative to the
// last corrected pose (SPEC 3.7): six independent [value, rate] filters.
class ConstantVelocityKalmanPredictor : public MotionPredictor {
 public:
  explicit ConstantVelocityKalmanPredictor(const MotionPredictorOptions& options);
  using MotionPredictor::Correct;
  void Reset(const Rigid3d& world_from_obj) override;
  Rigid3d Predict(double dt_s) override;
  void Correct(const Rigid3d& world_from_obj, double confidence) override;
  Vector6d Velocity() const override;
  Rigid3d Pose() const override;

 private:
  struct Axis {  // state [x, xdot] and its covariance
    double x = 0, v = 0;
    double pxx = 0, pxv = 0, pvv = 0;
  };
  MotionPredictorOptions options_;
  Axis axes_[6];  // 0-2 position (m), 3-5 rotation vector relative to reference_ (rad)
  Eigen::Quaterniond reference_ = Eigen::Quaterniond::Identity();
};

// Predicts no motion: the next pose is the last one at least `min_confidence` confident.
class HoldPredictor : public MotionPredictor {
 public:
  explicit HoldPredictor(double min_confidence = 0.0) : min_confidence_(min_confidence) {}
  using MotionPredictor::Correct;
  void Reset(const Rigid3d& world_from_obj) override { pose_ = world_from_obj; }
  Rigid3d Predict(double) override { return pose_; }
  void Correct(const Rigid3d& world_from_obj, double confidence) override {
    if (confidence >= min_confidence_) pose_ = world_from_obj;
  }
  Vector6d Velocity() const override { return Vector6d::Zero(); }
  Rigid3d Pose() const override { return pose_; }

 private:
  double min_confidence_;
  Rigid3d pose_;
};

// The predictor chosen by `options.type`.
std::unique_ptr<MotionPredictor> MakeMotionPredictor(const MotionPredictorOptions& options);

}  // namespace unseen
