// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The convoy controller on its own, without images: the lead's exact poses (optionally
// with noise) are measured, the follower is a unicycle under the commands.
#include "unseen/apps/convoy_controller.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "unseen/util/error.h"

namespace unseen {
namespace {

constexpr double kDt = 1.0 / 30.0;

// Distance of `p` from the polyline `path`.
double DistanceToPath(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& path) {
  double best = (p - path.front()).norm();
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const Eigen::Vector2d a = path[i], b = path[i + 1];
    const double len2 = (b - a).squaredNorm();
    const double u = len2 > 0 ? std::clamp((p - a).dot(b - a) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (a + u * (b - a) - p).norm());
  }
  return best;
}

struct FollowRun {
  std::vector<double> separation_error_m;  // along the lead's path, per frame
  double max_cross_track_m = 0.0;
  int max_stored = 0;
  std::vector<ConvoyCommand> commands;
};

// Lead and follower start at rest, D apart along +y; the lead accelerates at
// `lead_accel` to `lead_speed` and turns at `yaw_rate(t)`. Separation error: the lead's
// arc length minus the follower's projection's, minus D (straight runs: the y gap).
FollowRun Simulate(int frames, double lead_speed, double lead_accel,
                   const std::function<double(double)>& yaw_rate, double noise_m = 0.0,
                   ConvoyControllerOptions options = {}) {
  ConvoyController controller(options);
  VehicleState lead, follower;
  lead.pose = {Eigen::Vector2d(0, options.separation_m), M_PI / 2};
  follower.pose = {Eigen::Vector2d(0, 0), M_PI / 2};
  controller.Reset(lead.pose);
  std::vector<Eigen::Vector2d> lead_path = {follower.pose.position, lead.pose.position};
  std::vector<double> arc = {0.0, options.separation_m};
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, noise_m);
  FollowRun run;
  for (int k = 0; k < frames; ++k) {
    PlanarPose measured = lead.pose;
    if (noise_m > 0) measured.position += Eigen::Vector2d(noise(rng), noise(rng));
    const ConvoyCommand c = controller.Step(follower, measured);
    run.commands.push_back(c);
    run.max_stored = std::max(run.max_stored, c.stored_poses);
    // Every stored pose is ahead of the follower after the step.
    for (const PlanarPose& p : controller.Path()) {
      EXPECT_GT((p.position - follower.pose.position).dot(follower.pose.Direction()), 0.0)
          << "frame " << k;
    }
    follower = IntegrateUnicycle(follower, c.acceleration_m_s2, c.angular_velocity_rad_s, kDt,
                                 options.max_speed_m_s);
    const double accel = lead.speed_m_s < lead_speed ? lead_accel : 0.0;
    lead = IntegrateUnicycle(lead, accel, yaw_rate(k * kDt), kDt, lead_speed);
    arc.push_back(arc.back() + (lead.pose.position - lead_path.back()).norm());
    lead_path.push_back(lead.pose.position);
    // The follower's projection on the lead's path.
    double best = 1e9, best_arc = 0;
    for (std::size_t i = 0; i + 1 < lead_path.size(); ++i) {
      const Eigen::Vector2d a = lead_path[i], b = lead_path[i + 1];
      const double len2 = (b - a).squaredNorm();
      const double u =
          len2 > 0 ? std::clamp((follower.pose.position - a).dot(b - a) / len2, 0.0, 1.0) : 0.0;
      const double d = (a + u * (b - a) - follower.pose.position).norm();
      if (d < best) best = d, best_arc = arc[i] + u * std::sqrt(len2);
    }
    run.separation_error_m.push_back(arc.back() - best_arc - options.separation_m);
    run.max_cross_track_m =
        std::max(run.max_cross_track_m, DistanceToPath(follower.pose.position, lead_path));
  }
  return run;
}

TEST(ConvoyController, FollowsAStraightLineAtTheSetSeparation) {
  const FollowRun run = Simulate(240, 0.5, 0.5, [](double) { return 0.0; });
  // Settled after 4 s (the lead reached its speed after 1 s).
  for (int k = 120; k < 240; ++k) {
    EXPECT_NEAR(run.separation_error_m[k], 0.0, 2e-4) << "frame " << k;
  }
  EXPECT_LT(run.max_cross_track_m, 1e-6);
  // While the lead accelerates, within a few mm.
  for (double e : run.separation_error_m) EXPECT_LT(std::abs(e), 0.005);
}

TEST(ConvoyController, StaysOnTheLeadsPathThroughTurns) {
  // Left for 4 s at 30°/s, then right: radius 1.1 m at 0.6 m/s.
  const auto yaw = [](double t) {
    if (t < 1.5) return 0.0;
    return (t < 5.5 ? 1.0 : -1.0) * 30.0 * M_PI / 180.0;
  };
  const FollowRun run = Simulate(300, 0.6, 0.6, yaw);
  EXPECT_LT(run.max_cross_track_m, 0.0015);
  for (int k = 60; k < 300; ++k) EXPECT_LT(std::abs(run.separation_error_m[k]), 0.003);
}

TEST(ConvoyController, NoisyMeasurementsStillFollow) {
  // 0.5 mm of measurement noise, about the thesis's jitter at 300 mm.
  const FollowRun run = Simulate(
      300, 0.72, 0.36, [](double t) { return t > 3 ? 0.3 : 0.0; }, 0.0005);
  EXPECT_LT(run.max_cross_track_m, 0.003);
  for (int k = 60; k < 300; ++k) EXPECT_LT(std::abs(run.separation_error_m[k]), 0.006);
}

TEST(ConvoyController, DropsPassedPoses) {
  ConvoyControllerOptions options;
  const FollowRun run = Simulate(
      300, 0.72, 0.72, [](double) { return 0.0; }, 0.0, options);
  // At speed, the D / (v dt) = 12.5 poses between the vehicles, not all 300 measured;
  // never more than D / min_spacing.
  EXPECT_LE(run.commands.back().stored_poses, 14);
  EXPECT_GE(run.commands.back().stored_poses, 11);
  EXPECT_LE(run.max_stored, options.separation_m / options.min_spacing_m + 2);
}

TEST(ConvoyController, StoresNoPosesWhileTheLeadStands) {
  ConvoyController controller;
  const PlanarPose lead{Eigen::Vector2d(0, 0.3), M_PI / 2};
  controller.Reset(lead);
  VehicleState follower;
  follower.pose.heading_rad = M_PI / 2;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.0005);
  ConvoyCommand c;
  for (int k = 0; k < 100; ++k) {
    PlanarPose measured = lead;
    measured.position += Eigen::Vector2d(noise(rng), noise(rng));
    c = controller.Step(follower, measured);
  }
  EXPECT_EQ(c.stored_poses, 1);
  EXPECT_NEAR(c.following_distance_m, 0.3, 0.002);
  EXPECT_NEAR(c.look_ahead_angle_rad, 0.0, 0.01);
  EXPECT_EQ(c.angular_velocity_rad_s, 0.0);  // no turning on the spot
}

TEST(ConvoyController, FollowsTheStoredPathWithoutMeasurements) {
  ConvoyController controller;
  controller.Reset({Eigen::Vector2d(0, 0.3), M_PI / 2});
  VehicleState follower;
  follower.pose.heading_rad = M_PI / 2;
  follower.speed_m_s = 0.5;
  const ConvoyCommand c = controller.Step(follower, std::nullopt);
  EXPECT_FALSE(c.measured);
  EXPECT_NEAR(c.following_distance_m, 0.3, 1e-12);
  EXPECT_LT(c.acceleration_m_s2, 0.0);  // the lead seems to stand: slow down
}

TEST(ConvoyController, MeasuresDistanceAlongThePath) {
  ConvoyControllerOptions options;
  options.min_spacing_m = 0.0;
  ConvoyController controller(options);
  // An L-shaped stored path: (0, 0.2) then (0.1, 0.2); the follower at the origin.
  controller.Reset({Eigen::Vector2d(0, 0.2), 0.0});
  VehicleState follower;
  follower.pose.heading_rad = M_PI / 2;
  const ConvoyCommand c = controller.Step(follower, PlanarPose{Eigen::Vector2d(0.1, 0.2), 0.0});
  EXPECT_NEAR(c.following_distance_m, 0.3, 1e-12);     // (4.29)
  EXPECT_NEAR(c.look_ahead_angle_rad, 0.0, 1e-12);     // (4.30): p_j = (0, 0.1)
  EXPECT_NEAR(c.heading_error_rad, -M_PI / 2, 1e-12);  // (4.31): P_1 faces +x
}

TEST(ConvoyController, IntegratesAnArc) {
  VehicleState s;
  s.speed_m_s = 1.0;
  // A quarter circle of radius 1 m: ω = 1 rad/s for π/2 s in 100 steps.
  for (int k = 0; k < 100; ++k) s = IntegrateUnicycle(s, 0.0, 1.0, M_PI / 200, 10.0);
  EXPECT_NEAR(s.pose.position.x(), 1.0, 1e-9);
  EXPECT_NEAR(s.pose.position.y(), 1.0, 1e-9);
  EXPECT_NEAR(s.pose.heading_rad, M_PI / 2, 1e-9);
  // No reversing.
  s = IntegrateUnicycle(s, -100.0, 0.0, 0.1, 10.0);
  EXPECT_EQ(s.speed_m_s, 0.0);
}

TEST(ConvoyController, OptionsCheckRejectsNonsense) {
  EXPECT_NO_THROW(ConvoyControllerOptions().Check());
  const auto rejects = [](const std::function<void(ConvoyControllerOptions*)>& edit) {
    ConvoyControllerOptions o;
    edit(&o);
    EXPECT_THROW(o.Check(), Error);
    EXPECT_THROW(ConvoyController{o}, Error);
  };
  rejects([](ConvoyControllerOptions* o) { o->separation_m = 0; });
  rejects([](ConvoyControllerOptions* o) { o->separation_gain = -1; });
  rejects([](ConvoyControllerOptions* o) { o->look_ahead_m = 0; });
  rejects([](ConvoyControllerOptions* o) { o->min_spacing_m = o->look_ahead_m; });
  rejects([](ConvoyControllerOptions* o) { o->lead_speed_frames = 0; });
  rejects([](ConvoyControllerOptions* o) { o->separation_gain = 5000; });      // unstable step
  EXPECT_THROW(ConvoyController().Step(VehicleState(), std::nullopt), Error);  // no Reset
}

}  // namespace
}  // namespace unseen
