// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/flow_solver.h"

#include <algorithm>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "unseen/track/flow_jacobian.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

// Equations of `n` random surface pixels of a camera, consistent with `twist` (world frame),
// `outliers` of them with a wrong right-hand side.
FlowEquations MakeEquations(const PinholeCamera& cam, const Rigid3d& world_from_cam,
                            const Eigen::Vector3d& origin_world, const Vector6d& twist, int n,
                            int outliers, std::mt19937* rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  FlowEquations eq;
  eq.world_from_cam_rotation = world_from_cam.RotationMatrix();
  const Rigid3d cam_from_world = world_from_cam.Inverse();
  const Eigen::Vector3d o_c = cam_from_world * origin_world;
  const float o[3] = {float(o_c.x()), float(o_c.y()), float(o_c.z())};
  for (int i = 0; i < n; ++i) {
    const double x = cam.cx + 60 * u(*rng), y = cam.cy + 60 * u(*rng);
    const double z = o_c.z() + 0.05 * u(*rng);
    const double gx = 0.1 * u(*rng), gy = 0.1 * u(*rng);
    const Matrix26d j =
        ImageMotionJacobian(cam, cam_from_world, origin_world, Eigen::Vector2d(x, y), z);
    const double flow_dot_g = (Eigen::Vector2d(gx, gy).transpose() * j * twist)(0);
    float row[6];
    FlowRowInCamera(float(cam.fx), float(cam.fy), float(cam.cx), float(cam.cy), o, float(x),
                    float(y), float(z), float(gx), float(gy), row);
    float b = static_cast<float>(flow_dot_g);
    if (i < outliers) b += 0.1f * (u(*rng) > 0 ? 1.0f : -1.0f);
    eq.Add(row, b, static_cast<float>(1.0 / std::hypot(gx, gy)));
  }
  return eq;
}

PinholeCamera Camera() { return PinholeCamera::Centered(512, 256, 837.3); }

TEST(FlowSolver, RecoversTheTwistFromExactEquations) {
  std::mt19937 rng(3);
  Vector6d twist;
  twist << 0.002, -0.001, 0.004, 0.01, -0.02, 0.015;
  const Rigid3d world_from_cam(ExpSO3(Eigen::Vector3d(0.1, -0.3, 0.05)), Eigen::Vector3d(0.1, 0, 0));
  const Eigen::Vector3d origin = world_from_cam * Eigen::Vector3d(0.01, 0.02, 1.0);
  std::vector<FlowEquations> cams{MakeEquations(Camera(), world_from_cam, origin, twist, 2000, 0, &rng)};
  FlowSolverOptions options;
  options.kernel = RobustKernel::kNone;
  options.damping = 0.0;
  const FlowSolution s = SolveFlow(cams, options);
  ASSERT_TRUE(s.ok);
  EXPECT_LT((s.twist - twist).norm(), 1e-5 * twist.norm() + 1e-7) << s.twist.transpose();
  EXPECT_LT(s.final_rms_px, 1e-3);
}

TEST(FlowSolver, RobustKernelResistsOutliers) {
  std::mt19937 rng(5);
  Vector6d twist;
  twist << 0.003, 0.002, -0.002, -0.01, 0.02, 0.005;
  const Rigid3d world_from_cam;
  const Eigen::Vector3d origin(0.0, 0.0, 1.0);
  std::vector<FlowEquations> cams{MakeEquations(Camera(), world_from_cam, origin, twist, 3000, 450, &rng)};
  FlowSolverOptions plain;
  plain.kernel = RobustKernel::kNone;
  FlowSolverOptions huber;
  huber.irls_iterations = 5;
  FlowSolverOptions tukey;
  tukey.kernel = RobustKernel::kTukey;
  tukey.kernel_width = 4.685;
  tukey.irls_iterations = 5;
  const double e_plain = (SolveFlow(cams, plain).twist - twist).norm();
  const double e_huber = (SolveFlow(cams, huber).twist - twist).norm();
  const double e_tukey = (SolveFlow(cams, tukey).twist - twist).norm();
  EXPECT_LT(e_huber, 0.5 * e_plain);
  EXPECT_LT(e_tukey, 0.2 * e_plain);
}

TEST(FlowSolver, TwoCamerasInOneSolve) {
  std::mt19937 rng(9);
  Vector6d twist;
  twist << -0.004, 0.001, 0.006, 0.02, 0.01, -0.01;
  const Eigen::Vector3d origin(0.0, 0.0, 1.0);
  const Rigid3d cam_a;
  const Rigid3d cam_b(ExpSO3(Eigen::Vector3d(0, -0.6, 0)), Eigen::Vector3d(0.6, 0, 0.2));
  std::vector<FlowEquations> cams{MakeEquations(Camera(), cam_a, origin, twist, 500, 0, &rng),
                                  MakeEquations(Camera(), cam_b, origin, twist, 500, 0, &rng)};
  FlowSolverOptions options;
  options.kernel = RobustKernel::kNone;
  options.damping = 0.0;
  const FlowSolution s = SolveFlow(cams, options);
  ASSERT_TRUE(s.ok);
  EXPECT_LT((s.twist - twist).norm(), 1e-5);
}

TEST(FlowSolver, TooFewEquationsIsNotOk) {
  std::mt19937 rng(1);
  std::vector<FlowEquations> cams{
      MakeEquations(Camera(), Rigid3d(), Eigen::Vector3d(0, 0, 1), Vector6d::Zero(), 5, 0, &rng)};
  EXPECT_FALSE(SolveFlow(cams, FlowSolverOptions()).ok);
  EXPECT_FALSE(SolveFlow({}, FlowSolverOptions()).ok);
}

TEST(FlowSolver, AModalityAloneSolvesTheSameWhateverItsWeight) {
  std::mt19937 rng(11);
  Vector6d twist;
  twist << 0.002, 0.001, -0.003, 0.01, 0.0, -0.02;
  ModalityEquations m;
  m.cameras = {MakeEquations(Camera(), Rigid3d(), Eigen::Vector3d(0, 0, 1), twist, 800, 80, &rng)};
  FlowSolverOptions options;
  const FlowSolution a = SolveJoint({&m}, options);
  m.model.weight = 1000.0;
  const FlowSolution b = SolveJoint({&m}, options);
  ASSERT_TRUE(a.ok && b.ok);
  EXPECT_LT((a.twist - b.twist).norm(), 1e-6 * twist.norm());
  ASSERT_EQ(a.modalities.size(), 1u);
  EXPECT_EQ(a.modalities[0].equations, 800);
  EXPECT_GT(a.modalities[0].noise, 0.0);
}

TEST(FlowSolver, ModalitiesAreWeighedByTheirNoise) {
  // Two modalities of the same motion, one 100x noisier: weighed by their measured noise,
  // the joint solution is about as good as the precise one alone; weighed alike, the noisy
  // one spoils it.
  std::mt19937 rng(13);
  Vector6d truth;
  truth << 0.002, 0.001, -0.003, 0.01, 0.0, -0.02;
  ModalityEquations precise, noisy;
  precise.cameras = {
      MakeEquations(Camera(), Rigid3d(), Eigen::Vector3d(0, 0, 1), truth, 600, 0, &rng)};
  noisy.cameras = {
      MakeEquations(Camera(), Rigid3d(), Eigen::Vector3d(0, 0, 1), truth, 600, 0, &rng)};
  std::normal_distribution<float> small(0.0f, 1e-4f), large(0.0f, 1e-2f);
  for (float& b : precise.cameras[0].rhs) b += small(rng);
  for (float& b : noisy.cameras[0].rhs) b += large(rng);
  precise.model.min_noise = noisy.model.min_noise = 1e-6;
  FlowSolverOptions options;
  options.damping = 0.0;
  const double alone = (SolveJoint({&precise}, options).twist - truth).norm();
  const FlowSolution s = SolveJoint({&noisy, &precise}, options);
  ASSERT_TRUE(s.ok);
  const double joint = (s.twist - truth).norm();
  ASSERT_EQ(s.modalities.size(), 2u);
  EXPECT_GT(s.modalities[0].noise, 10.0 * s.modalities[1].noise);
  precise.model.min_noise = noisy.model.min_noise = 1.0;  // both weighed 1 / 1^2
  const double alike = (SolveJoint({&noisy, &precise}, options).twist - truth).norm();
  EXPECT_LT(joint, 2.0 * alone) << joint << " vs " << alone;
  EXPECT_LT(joint, 0.3 * alike) << joint << " vs " << alike;
  // A modality with no equations is skipped; none at all is no solution.
  ModalityEquations empty;
  EXPECT_TRUE(SolveJoint({&precise, &empty, nullptr}, options).ok);
  EXPECT_FALSE(SolveJoint({&empty}, options).ok);
}

TEST(FlowSolver, TheUpdatesChiSquareIsAboutSixOnNoiseAloneAndLargeForARealMotion) {
  // The update's squared length under the information matrix (what the tracker's coarse
  // levels stop on): for equations of no motion whose right-hand sides are noise alone it
  // is chi-square with 6 degrees of freedom (mean 6); for a real motion it is far larger.
  std::mt19937 rng(17);
  std::normal_distribution<float> noise(0.0f, 1e-3f);
  FlowSolverOptions options;
  options.damping = 0.0;
  double sum = 0.0;
  const int trials = 200;
  for (int t = 0; t < trials; ++t) {
    ModalityEquations m;
    m.model.kernel = RobustKernel::kNone;
    m.model.min_noise = 1e-6;
    m.cameras = {MakeEquations(Camera(), Rigid3d(), Eigen::Vector3d(0, 0, 1), Vector6d::Zero(),
                               300, 0, &rng)};
    for (float& b : m.cameras[0].rhs) b += noise(rng);
    const FlowSolution s = SolveJoint({&m}, options);
    ASSERT_TRUE(s.ok);
    sum += s.twist.dot(s.information * s.twist);
  }
  const double mean = sum / trials;
  EXPECT_GT(mean, 4.5);
  EXPECT_LT(mean, 7.5);

  Vector6d motion;
  motion << 0.002, 0.001, -0.003, 0.01, 0.0, -0.02;
  ModalityEquations m;
  m.model.kernel = RobustKernel::kNone;
  m.model.min_noise = 1e-6;
  m.cameras = {MakeEquations(Camera(), Rigid3d(), Eigen::Vector3d(0, 0, 1), motion, 300, 0, &rng)};
  for (float& b : m.cameras[0].rhs) b += noise(rng);
  const FlowSolution s = SolveJoint({&m}, options);
  ASSERT_TRUE(s.ok);
  EXPECT_GT(s.twist.dot(s.information * s.twist), 10.0 * mean);
  // A failed solve has no information.
  ModalityEquations empty;
  EXPECT_EQ(SolveJoint({&empty}, options).information, Matrix6d::Zero());
}

TEST(FlowSolver, SwingsWithinNoiseOnlyWhenASmallUpdateTurnsBack) {
  // Information of 1e4 per unit twist: an update of 0.01 along an axis has chi-square 1.
  const Matrix6d information = 1e4 * Matrix6d::Identity();
  Vector6d forward = Vector6d::Zero(), back = Vector6d::Zero(), aside = Vector6d::Zero();
  forward(3) = 0.01;
  back(3) = -0.01;
  aside(4) = 0.01;
  EXPECT_TRUE(SwingsWithinNoise(forward, back, information, 6.0));
  EXPECT_FALSE(SwingsWithinNoise(forward, forward, information, 6.0));  // still going on
  EXPECT_FALSE(SwingsWithinNoise(forward, aside, information, 6.0));    // not back
  EXPECT_FALSE(SwingsWithinNoise(Vector6d::Zero(), back, information, 6.0));  // first round
  EXPECT_FALSE(SwingsWithinNoise(forward, 3.0 * back, information, 6.0));  // chi-square 9
  EXPECT_TRUE(SwingsWithinNoise(forward, 3.0 * back, information, 10.0));
  EXPECT_FALSE(SwingsWithinNoise(forward, back, information, 0.0));  // off
  // The metric is the information's: a turn back in a direction it barely holds counts
  // even when the Euclidean inner product says otherwise.
  Matrix6d skewed = information;
  skewed(3, 3) = 1e6;
  Vector6d mostly_aside = aside;
  mostly_aside(3) = -0.001;  // back along the well-held axis, a little
  const Vector6d previous = forward + 2.0 * aside;  // Euclidean: mostly_aside goes on with it
  ASSERT_GT(previous.dot(mostly_aside), 0.0);
  EXPECT_TRUE(SwingsWithinNoise(previous, mostly_aside, skewed, 6.0));
}

TEST(FlowSolver, AModalitysDampingShortensItsOwnStepOnly) {
  // Exact equations: undamped, the solve finds the twist; a modality's damping shortens
  // the step while it is alone, and much less next to a modality that determines the
  // motion far better.
  std::mt19937 rng(17);
  Vector6d truth;
  truth << 0.002, 0.001, -0.003, 0.01, 0.0, -0.02;
  ModalityEquations damped, strong;
  damped.cameras = {
      MakeEquations(Camera(), Rigid3d(), Eigen::Vector3d(0, 0, 1), truth, 400, 0, &rng)};
  strong.cameras = {
      MakeEquations(Camera(), Rigid3d(), Eigen::Vector3d(0, 0, 1), truth, 400, 0, &rng)};
  damped.model.kernel = strong.model.kernel = RobustKernel::kNone;
  damped.model.min_noise = strong.model.min_noise = 1.0;  // fixed weights: 1 and 100
  strong.model.weight = 100.0;
  FlowSolverOptions options;
  options.damping = 0.0;
  const Vector6d plain = SolveJoint({&damped}, options).twist;
  EXPECT_LT((plain - truth).norm(), 1e-4 * truth.norm());
  damped.model.damping = 0.1;
  const Vector6d alone = SolveJoint({&damped}, options).twist;
  EXPECT_LT(alone.norm(), 0.97 * truth.norm());
  const Vector6d joint = SolveJoint({&damped, &strong}, options).twist;
  EXPECT_LT((joint - truth).norm(), 0.3 * (alone - truth).norm());
  damped.model.damping = 1.0;
  EXPECT_THROW(damped.model.Check("region"), Error);
}

TEST(FlowSolver, TrimmedRmsLeavesOutTheLargestResiduals) {
  ModalityEquations m;
  m.cameras.resize(2);
  const float row[6] = {1, 0, 0, 0, 0, 0};
  // Nine unit offsets over two cameras and one of 10 (an occluded line).
  for (int i = 0; i < 9; ++i) m.cameras[i % 2].Add(row, (i % 2 ? -1.0f : 1.0f), 1.0f);
  m.cameras[1].Add(row, 10.0f, 1.0f);
  EXPECT_NEAR(m.TrimmedRms(1.0), std::sqrt(109.0 / 10.0), 1e-6);
  EXPECT_NEAR(m.TrimmedRms(0.9), 1.0, 1e-6);
  EXPECT_NEAR(m.TrimmedRms(0.05), 1.0, 1e-6);  // at least one equation
  // Residuals are scaled by inv_grad_norm as in the solve.
  m.cameras[0].inv_grad_norm.assign(m.cameras[0].inv_grad_norm.size(), 2.0f);
  EXPECT_NEAR(m.TrimmedRms(0.4), 1.0, 1e-6);                   // camera 1's four 1s
  EXPECT_NEAR(m.TrimmedRms(0.9), std::sqrt(24.0 / 9.0), 1e-6);  // and camera 0's five 2s
  EXPECT_THROW(m.TrimmedRms(0.0), Error);
  EXPECT_THROW(m.TrimmedRms(1.5), Error);
  EXPECT_EQ(ModalityEquations().TrimmedRms(0.9), 0.0);
}

TEST(FlowSolver, RobustSigmaIsTheMedianOfItsSpread) {
  // The radix selection must give exactly the median std::nth_element gives, over ties,
  // zeros, tiny and huge magnitudes and every size up to the 1 024 it samples (and beyond,
  // where it takes every k-th value).
  std::mt19937 rng(5);
  std::lognormal_distribution<float> spread(-2.0f, 3.0f);
  for (int n : {1, 2, 3, 7, 64, 1000, 1023, 1024, 1025, 5000}) {
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<float> values(n);
      for (float& v : values) v = trial % 3 == 0 ? float(rng() % 4) : spread(rng);
      if (trial % 5 == 1) values[n / 2] = 0.0f;
      const size_t stride = (values.size() + 1023) / 1024;
      std::vector<float> kept;
      for (size_t i = 0; i < values.size(); i += stride) kept.push_back(values[i]);
      std::nth_element(kept.begin(), kept.begin() + kept.size() / 2, kept.end());
      const double expected = 1.4826 * kept[kept.size() / 2];
      EXPECT_EQ(RobustSigma(&values), expected) << "n " << n << " trial " << trial;
    }
  }
  std::vector<float> signed_values = {-3.0f, 1.0f, -0.5f, 2.0f, 0.25f};  // not magnitudes
  EXPECT_EQ(RobustSigma(&signed_values), 1.4826 * 0.25f);
  std::vector<float> none;
  EXPECT_EQ(RobustSigma(&none), 0.0);
}

TEST(FlowSolver, ASubordinateModalitySettlesOnlyWhatTheOthersLeaveOpen) {
  // The leading modality determines five of the six twist components and nothing of the
  // last; a subordinate one, biased, sees all six. Subordinate, it settles the last
  // component and leaves the others to the lead; an equal partner, it pulls all six.
  std::mt19937 rng(23);
  std::normal_distribution<float> n01(0.0f, 1.0f);
  Vector6d lead_truth, biased;
  lead_truth << 0.002, 0.001, -0.003, 0.01, 0.005, -0.02;
  biased = lead_truth + Vector6d::Constant(0.004);
  // Rows in pairs whose last entries differ in sign only: the last component is
  // uncorrelated with the others, so the open one's estimate is the subordinate's own.
  auto equations = [&](const Vector6d& twist, bool sees_last) {
    FlowEquations eq;
    for (int i = 0; i < 300; ++i) {
      float row[6];
      for (int k = 0; k < 6; ++k) row[k] = k < 5 || sees_last ? n01(rng) : 0.0f;
      for (int sign : {1, -1}) {
        row[5] *= static_cast<float>(sign);
        const Eigen::Map<const Eigen::Matrix<float, 6, 1>> a(row);
        eq.Add(row, a.dot(twist.cast<float>()), 1.0f);
      }
    }
    return eq;
  };
  ModalityEquations lead, subordinate;
  lead.cameras = {equations(lead_truth, false)};
  subordinate.cameras = {equations(biased, true)};
  for (ModalityEquations* m : {&lead, &subordinate}) {
    m->model.kernel = RobustKernel::kNone;
    m->model.min_noise = m->model.max_noise = 1.0;  // fixed weights
  }
  subordinate.model.weight = 0.3;  // about 0.3 of the lead's information where both see
  FlowSolverOptions options;
  options.damping = 0.0;
  const Vector6d partner = SolveJoint({&lead, &subordinate}, options).twist;
  subordinate.model.subordinate_ratio = 1.0;
  const Vector6d settled = SolveJoint({&lead, &subordinate}, options).twist;
  // The five components the lead sees: the lead's own; pulled toward the bias as a partner.
  EXPECT_LT((settled - lead_truth).head<5>().norm(), 0.05 * 0.004) << settled.transpose();
  EXPECT_GT((partner - lead_truth).head<5>().norm(), 0.3 * 0.004) << partner.transpose();
  // The open one: the subordinate's, both ways.
  EXPECT_NEAR(settled(5), biased(5), 0.1 * 0.004);
  EXPECT_NEAR(partner(5), biased(5), 0.3 * 0.004);
  // Alone, a subordinate modality solves as any other.
  EXPECT_LT((SolveJoint({&subordinate}, options).twist - biased).norm(), 1e-4);
  subordinate.model.subordinate_ratio = -1.0;
  EXPECT_THROW(subordinate.model.Check("photometric"), Error);
}

TEST(FlowSolver, OptionsCheck) {
  FlowSolverOptions o;
  EXPECT_NO_THROW(o.Check());
  o.kernel_width = -1;
  EXPECT_THROW(o.Check(), Error);
  EXPECT_THROW(ParseRobustKernel("cauchy"), Error);
  EXPECT_EQ(ParseRobustKernel("tukey"), RobustKernel::kTukey);
}

}  // namespace
}  // namespace unseen
