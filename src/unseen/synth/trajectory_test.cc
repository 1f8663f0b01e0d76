// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/synth/trajectory.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "unseen/io/pose_stream.h"
#include "unseen/io/sequence.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

// SPEC 8 Fig. 4.7 zig-zag (top view x right, z away), metres.
WaypointTrajectoryOptions ZigZag(double speed_m_s) {
  WaypointTrajectoryOptions o;
  o.origin_m = {0.0, 0.0, 1.0};
  o.waypoints_m = {{0, 0, 0},       {0.06, 0, 0.04}, {0.10, 0, 0},
                   {0.16, 0, 0.08}, {0.20, 0, 0.04}, {0.24, 0, 0.12}};
  o.speed_m_s = speed_m_s;
  return o;
}

TEST(ComposeRotations, AppliesStepsInOrderAboutObjectAxes) {
  const Eigen::Quaterniond r =
      ComposeRotations({{Eigen::Vector3d::UnitX(), 90.0}, {Eigen::Vector3d::UnitY(), 90.0}});
  // R = Rx(90) Ry(90): z -> (Ry 90) -> x -> (Rx 90) -> x;  x -> -z -> y.
  EXPECT_TRUE((r * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_TRUE((r * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  // The development sequences' initial rotation (x 20 deg, y 30 deg) as in their ground truth.
  const Eigen::Matrix3d dev =
      ComposeRotations({{Eigen::Vector3d::UnitX(), 20.0}, {Eigen::Vector3d::UnitY(), 30.0}})
          .toRotationMatrix();
  Eigen::Matrix3d expected;
  expected << 0.8660254038, 0.0, 0.5, 0.1710100717, 0.9396926208, -0.2961981327, -0.4698463104,
      0.3420201433, 0.8137976813;
  EXPECT_TRUE(dev.isApprox(expected, 1e-9));
  EXPECT_THROW(ComposeRotations({{Eigen::Vector3d::Zero(), 10.0}}), Error);
  EXPECT_THROW(ComposeRotations({{Eigen::Vector3d::UnitX(), NAN}}), Error);
}

TEST(WaypointTrajectory, PositionsAtKnownTimes) {
  const WaypointTrajectory traj(ZigZag(0.04));
  const double l0 = std::hypot(0.06, 0.04);
  const double l1 = std::hypot(0.04, 0.04);
  EXPECT_NEAR(traj.PathLengthM(), l0 + l1 + std::hypot(0.06, 0.08) + l1 + std::hypot(0.04, 0.08),
              1e-12);
  EXPECT_TRUE(traj.WorldFromObj(0.0).translation().isApprox(Eigen::Vector3d(0, 0, 1), 1e-12));
  // Half-way along the first segment.
  EXPECT_TRUE(traj.WorldFromObj(0.5 * l0 / 0.04)
                  .translation()
                  .isApprox(Eigen::Vector3d(0.03, 0, 1.02), 1e-12));
  // Exactly at the first corner, and a quarter into the second segment.
  EXPECT_TRUE(
      traj.WorldFromObj(l0 / 0.04).translation().isApprox(Eigen::Vector3d(0.06, 0, 1.04), 1e-12));
  EXPECT_TRUE(traj.WorldFromObj((l0 + 0.25 * l1) / 0.04)
                  .translation()
                  .isApprox(Eigen::Vector3d(0.07, 0, 1.03), 1e-12));
  // Held at the end.
  EXPECT_TRUE(traj.WorldFromObj(traj.EndTimeS() + 5.0)
                  .translation()
                  .isApprox(Eigen::Vector3d(0.24, 0, 1.12), 1e-12));
  EXPECT_NEAR(traj.EndTimeS(), traj.PathLengthM() / 0.04, 1e-12);
  // Before the start: at the first waypoint.
  EXPECT_TRUE(traj.WorldFromObj(-1.0).translation().isApprox(Eigen::Vector3d(0, 0, 1), 1e-12));
}

TEST(WaypointTrajectory, MovesAtConstantSpeed) {
  // Table 4.3's (120, 60) mm/s travelled as |v| = 134.16 mm/s.
  const double speed = Eigen::Vector2d(0.12, 0.06).norm();
  const WaypointTrajectory traj(ZigZag(speed));
  const double dt = 1.0 / 30.0;
  int frames_checked = 0;
  for (double t = 0.0; t + dt < traj.EndTimeS(); t += dt) {
    const Eigen::Vector3d a = traj.WorldFromObj(t).translation();
    const Eigen::Vector3d b = traj.WorldFromObj(t + dt).translation();
    // The chord is shorter than the arc only across a corner.
    EXPECT_LE((b - a).norm(), speed * dt + 1e-12);
    EXPECT_GT((b - a).norm(), 0.5 * speed * dt);
    ++frames_checked;
  }
  EXPECT_GT(frames_checked, 70);
  // Away from corners the chord equals the arc.
  EXPECT_NEAR(
      (traj.WorldFromObj(0.1).translation() - traj.WorldFromObj(0.1 + dt).translation()).norm(),
      speed * dt, 1e-12);
}

TEST(WaypointTrajectory, SpinAngleGrowsWithTime) {
  WaypointTrajectoryOptions o = ZigZag(0.04);
  o.initial_rotation = ComposeRotations({{Eigen::Vector3d::UnitX(), 20.0}});
  o.spin.axis = Eigen::Vector3d::UnitY();
  o.spin.rate_rad_s = 0.18;
  const WaypointTrajectory in_object(o);
  o.spin.world_frame = true;
  const WaypointTrajectory in_world(o);
  for (double t : {0.0, 1.0, 3.0, 7.5}) {
    const double expected = std::fmod(0.18 * t, 2.0 * M_PI);
    EXPECT_NEAR(AngleBetween(in_object.RotationAt(0.0), in_object.RotationAt(t)), expected, 1e-9);
    EXPECT_NEAR(AngleBetween(in_world.RotationAt(0.0), in_world.RotationAt(t)), expected, 1e-9);
    // World frame: the world vertical axis is the fixed axis of R(t) R(0)^-1.
    const Eigen::Quaterniond dw = in_world.RotationAt(t) * in_world.RotationAt(0.0).conjugate();
    EXPECT_TRUE((dw * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d::UnitY(), 1e-9));
    // Object frame: the object's own y axis is fixed: R(0)^-1 R(t) keeps y.
    const Eigen::Quaterniond dobj = in_object.RotationAt(0.0).conjugate() * in_object.RotationAt(t);
    EXPECT_TRUE((dobj * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d::UnitY(), 1e-9));
  }
  // With a tilted object the two differ.
  EXPECT_GT(AngleBetween(in_world.RotationAt(2.0), in_object.RotationAt(2.0)), 1e-3);
}

TEST(WaypointTrajectory, StartTimeDelaysMotion) {
  WaypointTrajectoryOptions o = ZigZag(0.04);
  o.start_time_s = 2.0;
  const WaypointTrajectory traj(o);
  EXPECT_TRUE(traj.WorldFromObj(1.9).translation().isApprox(Eigen::Vector3d(0, 0, 1), 1e-12));
  EXPECT_NEAR(traj.EndTimeS(), 2.0 + traj.PathLengthM() / 0.04, 1e-12);
}

TEST(WaypointTrajectory, RejectsBadOptions) {
  WaypointTrajectoryOptions o = ZigZag(0.0);
  EXPECT_THROW(WaypointTrajectory{o}, Error);
  o = ZigZag(0.04);
  o.waypoints_m.clear();
  EXPECT_THROW(WaypointTrajectory{o}, Error);
  o = ZigZag(0.04);
  o.waypoints_m[2].x() = NAN;
  EXPECT_THROW(WaypointTrajectory{o}, Error);
  o = ZigZag(0.04);
  o.spin.axis.setZero();
  o.spin.rate_rad_s = 1.0;
  EXPECT_THROW(WaypointTrajectory{o}, Error);
}

TEST(KeyframeTrajectory, InterpolatesAndHolds) {
  const Rigid3d a(Eigen::Quaterniond::Identity(), {0, 0, 1});
  const Rigid3d b(ExpSO3({0, 1.0, 0}), {0.1, 0, 1});
  const KeyframeTrajectory traj({{1.0, a}, {2.0, b}});
  EXPECT_TRUE(traj.WorldFromObj(0.0).translation().isApprox(a.translation()));
  EXPECT_TRUE(traj.WorldFromObj(3.0).translation().isApprox(b.translation()));
  const Rigid3d mid = traj.WorldFromObj(1.25);
  EXPECT_TRUE(mid.translation().isApprox(Eigen::Vector3d(0.025, 0, 1), 1e-12));
  EXPECT_NEAR(AngleBetween(a.rotation(), mid.rotation()), 0.25, 1e-9);
  EXPECT_DOUBLE_EQ(traj.EndTimeS(), 2.0);
  EXPECT_THROW(KeyframeTrajectory({}), Error);
  EXPECT_THROW(KeyframeTrajectory({{1.0, a}, {1.0, b}}), Error);
}

TEST(StaticTrajectory, HoldsPose) {
  const Rigid3d p(ExpSO3({0.1, 0.2, 0.3}), {0.01, 0.02, 0.9});
  const StaticTrajectory traj(p);
  EXPECT_TRUE(traj.WorldFromObj(12.0).translation().isApprox(p.translation()));
  EXPECT_NEAR(AngleBetween(traj.WorldFromObj(3.0).rotation(), p.rotation()), 0.0, 1e-12);
}

TEST(PoseFileTrajectory, ReadsStreamAndSkipsLostFrames) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "unseen_trajectory_test_poses.csv").string();
  std::vector<PoseRecord> records;
  for (int k = 0; k < 4; ++k) {
    PoseRecord r;
    r.frame = k;
    r.time_s = k / 10.0;
    r.status = k == 2 ? TrackStatus::kLost : TrackStatus::kTracking;
    r.world_from_obj = Rigid3d(ExpSO3({0, 0.1 * k, 0}), {0.01 * k, 0, 1});
    records.push_back(r);
  }
  WritePoseStream(path, records);
  const auto traj = LoadPoseFileTrajectory(path, 10.0);
  ASSERT_EQ(traj->keys().size(), 3u);
  // Frame 2 was lost: interpolated between frames 1 and 3.
  EXPECT_TRUE(traj->WorldFromObj(0.2).translation().isApprox(Eigen::Vector3d(0.02, 0, 1), 1e-9));
  EXPECT_NEAR(traj->EndTimeS(), 0.3, 1e-9);
  std::filesystem::remove(path);
  EXPECT_THROW(LoadPoseFileTrajectory(path, 10.0), Error);
}

// The development sequences were rendered by an independent renderer from scene.json files
// with these trajectories; their ground truth must agree with ours (checks the waypoint
// timing, the rotation composition and both spin frames).
TEST(WaypointTrajectory, MatchesDevelopmentSequenceGroundTruth) {
  const std::string root = std::string(UNSEEN_SOURCE_DIR) + "/../shared/data/sequences/";
  if (!std::filesystem::exists(root)) GTEST_SKIP() << "no development sequences at " << root;
  struct Case {
    const char* name;
    double speed_mm_s;
    std::vector<AxisRotation> initial;
    double spin_rate;
    bool world_frame;
  };
  const Case cases[] = {
      {"cube_white_zigzag",
       40.0,
       {{Eigen::Vector3d::UnitX(), 20}, {Eigen::Vector3d::UnitY(), 30}},
       0.15,
       false},
      {"sphere_clutter_spin", 30.0, {{Eigen::Vector3d::UnitX(), 90}}, 0.3, true},
  };
  for (const Case& c : cases) {
    if (!std::filesystem::exists(root + c.name)) continue;
    WaypointTrajectoryOptions o = ZigZag(c.speed_mm_s * 1e-3);
    o.initial_rotation = ComposeRotations(c.initial);
    o.spin.rate_rad_s = c.spin_rate;
    o.spin.world_frame = c.world_frame;
    const WaypointTrajectory traj(o);
    const Sequence seq = Sequence::Open(root + c.name);
    ASSERT_TRUE(seq.has_ground_truth());
    for (int k = 0; k < seq.num_frames(); k += 7) {
      const auto gt = seq.GroundTruth(k);
      ASSERT_TRUE(gt.has_value());
      const Rigid3d ours = traj.WorldFromObj(seq.frame_id(k) / seq.fps());
      EXPECT_LT((gt->translation() - ours.translation()).norm(), 1e-4) << c.name << " frame " << k;
      EXPECT_LT(AngleBetween(gt->rotation(), ours.rotation()), 1e-4) << c.name << " frame " << k;
    }
  }
}

}  // namespace
}  // namespace unseen
