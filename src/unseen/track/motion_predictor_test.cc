// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/motion_predictor.h"

#include <gtest/gtest.h>

#include "unseen/util/error.h"

namespace unseen {
namespace {

Rigid3d PoseAt(double t) {
  return Rigid3d(ExpSO3(Eigen::Vector3d(0.1, 0.6 * t, 0.05)),
                 Eigen::Vector3d(0.2 * t, -0.1 * t, 1.0 + 0.05 * t));
}

TEST(MotionPredictor, KalmanLearnsConstantVelocity) {
  ConstantVelocityKalmanPredictor kf{MotionPredictorOptions()};
  const double dt = 1.0 / 30;
  kf.Reset(PoseAt(0));
  for (int k = 1; k <= 30; ++k) {
    kf.Predict(dt);
    kf.Correct(PoseAt(k * dt));
  }
  const Rigid3d predicted = kf.Predict(dt);
  const PoseDifference d = Difference(predicted, PoseAt(31 * dt));
  EXPECT_LT(d.translation, 2e-4);
  EXPECT_LT(d.rotation_rad, 2e-3);
  const Vector6d v = kf.Velocity();
  EXPECT_NEAR(v(0), 0.2, 0.01);
  EXPECT_NEAR(v(1), -0.1, 0.01);
  EXPECT_NEAR(v(2), 0.05, 0.01);
  // Angular velocity of exp(0.6 t e_y) R0: world-frame, magnitude 0.6 rad/s.
  EXPECT_NEAR(v.tail<3>().norm(), 0.6, 0.03);
}

TEST(MotionPredictor, KalmanBeatsHoldOnSteadyMotion) {
  const double dt = 1.0 / 30;
  auto kf = MakeMotionPredictor(MotionPredictorOptions());
  MotionPredictorOptions hold_options;
  hold_options.type = PredictorType::kHold;
  auto hold = MakeMotionPredictor(hold_options);
  kf->Reset(PoseAt(0));
  hold->Reset(PoseAt(0));
  double err_kf = 0, err_hold = 0;
  for (int k = 1; k <= 20; ++k) {
    err_kf += Difference(kf->Predict(dt), PoseAt(k * dt)).translation;
    err_hold += Difference(hold->Predict(dt), PoseAt(k * dt)).translation;
    kf->Correct(PoseAt(k * dt));
    hold->Correct(PoseAt(k * dt));
  }
  EXPECT_LT(err_kf, 0.3 * err_hold);
  EXPECT_TRUE(hold->Velocity().isZero());
}

TEST(MotionPredictor, ResetStopsTheObject) {
  ConstantVelocityKalmanPredictor kf{MotionPredictorOptions()};
  kf.Reset(PoseAt(0));
  for (int k = 1; k <= 10; ++k) {
    kf.Predict(0.1);
    kf.Correct(PoseAt(k * 0.1));
  }
  kf.Reset(PoseAt(0));
  EXPECT_TRUE(kf.Velocity().isZero());
  EXPECT_LT(Difference(kf.Predict(0.1), PoseAt(0)).translation, 1e-12);
}

// The pose after `k` frames of steady motion and then one outlier 5 cm off along x fed
// with `confidence`, as the next prediction sees it.
Rigid3d PredictionAfterOutlier(MotionPredictor* p, double confidence) {
  const double dt = 1.0 / 30;
  p->Reset(PoseAt(0));
  for (int k = 1; k <= 20; ++k) {
    p->Predict(dt);
    p->Correct(PoseAt(k * dt));
  }
  p->Predict(dt);
  const Rigid3d truth = PoseAt(21 * dt);
  p->Correct(Rigid3d(truth.rotation(), truth.translation() + Eigen::Vector3d(0.05, 0, 0)),
             confidence);
  return p->Predict(dt);
}

TEST(MotionPredictor, LessConfidentPosesMoveThePredictionLess) {
  MotionPredictorOptions options;
  options.min_confidence = 0.2;
  options.confidence_power = 4.0;
  ConstantVelocityKalmanPredictor kf(options);
  const Rigid3d truth = PoseAt(22.0 / 30);
  const double confident = Difference(PredictionAfterOutlier(&kf, 1.0), truth).translation;
  const double doubtful = Difference(PredictionAfterOutlier(&kf, 0.3), truth).translation;
  const double ignored = Difference(PredictionAfterOutlier(&kf, 0.1), truth).translation;
  EXPECT_GT(confident, 0.03);  // a trusted pose is followed (and its jump taken as motion)
  EXPECT_LT(doubtful, 0.5 * confident);
  EXPECT_LT(ignored, 1e-3);    // below the floor the filter coasts on the steady motion
  // The hold predictor keeps the last pose that reached the floor.
  HoldPredictor hold(0.2);
  EXPECT_LT(Difference(PredictionAfterOutlier(&hold, 0.1), PoseAt(20.0 / 30)).translation, 1e-12);
  EXPECT_NEAR(Difference(PredictionAfterOutlier(&hold, 0.3), truth).translation, 0.05, 0.01);
}

TEST(MotionPredictor, RejectsBadInput) {
  MotionPredictorOptions o;
  o.position_sigma = 0;
  EXPECT_THROW(o.Check(), Error);
  EXPECT_THROW(ParsePredictorType("ukf"), Error);
  ConstantVelocityKalmanPredictor kf{MotionPredictorOptions()};
  EXPECT_THROW(kf.Predict(0.0), Error);
  EXPECT_THROW(kf.Correct(PoseAt(0), 1.5), Error);
  o = MotionPredictorOptions();
  o.min_confidence = 0.0;
  EXPECT_THROW(o.Check(), Error);
}

}  // namespace
}  // namespace unseen
