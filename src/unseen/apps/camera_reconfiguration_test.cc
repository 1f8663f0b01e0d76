// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/apps/camera_reconfiguration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "unseen/util/error.h"

namespace unseen {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// A camera 1 m behind the origin looking along +z, on a 1 m rail along x.
StageCamera RailCamera() {
  StageCamera c;
  c.name = "rail";
  c.rail_origin_m = {0.0, -1.0};
  c.rail_min_m = -0.5;
  c.rail_max_m = 0.5;
  c.rail_speed_m_s = 0.2;
  c.rail_step_m = 0.02;
  c.pan_min_rad = -40 * kDeg;
  c.pan_max_rad = 40 * kDeg;
  c.pan_speed_rad_s = 40 * kDeg;
  c.pan_step_rad = 1 * kDeg;
  c.focus_distance_m = 1.0;
  return c;
}

BoundingEllipse ObjectAt(double x, double z) {
  BoundingEllipse e;
  e.centre_m = {x, z};
  e.semi_axes_m = Eigen::Vector2d::Constant(0.068);
  return e;
}

// One rail camera, a column half-way to a still object at the origin.
ReconfigurationConfig HiddenObjectConfig() {
  ReconfigurationConfig c;
  c.track = false;
  c.frames = 60;
  c.path_m = {{0.0, 0.0}};
  c.path_speed_m_s = 0.0;
  c.spin_rad_s = 0.0;
  c.columns = {{{0.0, -0.5}, 0.06}};
  c.cameras = {RailCamera()};
  c.planner.assigned_cameras = 1;
  return c;
}

TEST(CameraAgent, RankedPosesRespectStageLimitsAndActuatorSpeeds) {
  StageCamera camera = RailCamera();
  camera.home = {0.46, 35 * kDeg};  // near the limits
  const CameraAgent agent(camera);
  EXPECT_EQ(agent.num_poses(), 51 * 81);
  const int from = agent.NearestPose(camera.home);
  const double dt = 0.2;
  const std::vector<RankedPose> ranked =
      agent.Rank(from, dt, ObjectAt(0.3, 0.5), std::vector<Column>{}, VisibilityOptions());
  // 0.2 m/s * 0.2 s = 2 rail steps, but only 2 more to the limit; 8 pan steps, 5 to the limit.
  EXPECT_EQ(ranked.size(), size_t{(2 + 1 + 2) * (8 + 1 + 5)});
  const StageState now = agent.Pose(from);
  for (size_t i = 0; i < ranked.size(); ++i) {
    const StageState s = agent.Pose(ranked[i].index);
    EXPECT_GE(s.rail_m, camera.rail_min_m - 1e-12);
    EXPECT_LE(s.rail_m, camera.rail_max_m + 1e-12);
    EXPECT_GE(s.pan_rad, camera.pan_min_rad - 1e-12);
    EXPECT_LE(s.pan_rad, camera.pan_max_rad + 1e-12);
    EXPECT_LE(std::abs(s.rail_m - now.rail_m), camera.rail_speed_m_s * dt + 1e-9);
    EXPECT_LE(std::abs(s.pan_rad - now.pan_rad), camera.pan_speed_rad_s * dt + 1e-9);
    EXPECT_TRUE(agent.Reachable(from, ranked[i].index, dt));
    if (i > 0) {
      EXPECT_GE(ranked[i - 1].visibility, ranked[i].visibility);
    }
  }
  EXPECT_FALSE(agent.Reachable(from, agent.NearestPose({0.0, 0.0}), dt));
}

TEST(CameraReconfiguration, SimulatedStagesStayWithinLimitsAndSpeeds) {
  ReconfigurationConfig config = HiddenObjectConfig();
  config.path_m = {{-0.3, 0.0}, {0.3, 0.2}};
  config.path_speed_m_s = 0.3;
  const ReconfigurationResult r = RunReconfiguration(config);
  const StageCamera& c = config.cameras[0];
  double moved = 0.0;
  for (size_t k = 1; k < r.frames.size(); ++k) {
    for (int v = 0; v < kNumVariants; ++v) {
      const StageState a = r.frames[k - 1].states[v][0], b = r.frames[k].states[v][0];
      EXPECT_LE(std::abs(b.rail_m - a.rail_m), c.rail_speed_m_s / config.fps + 1e-12);
      EXPECT_LE(std::abs(b.pan_rad - a.pan_rad), c.pan_speed_rad_s / config.fps + 1e-12);
      EXPECT_GE(b.rail_m, c.rail_min_m - 1e-12);
      EXPECT_LE(b.rail_m, c.rail_max_m + 1e-12);
      EXPECT_GE(b.pan_rad, c.pan_min_rad - 1e-12);
      EXPECT_LE(b.pan_rad, c.pan_max_rad + 1e-12);
      moved += std::abs(b.rail_m - a.rail_m) + std::abs(b.pan_rad - a.pan_rad);
    }
  }
  EXPECT_GT(moved, 0.1);
}

TEST(CameraReconfiguration, CameraThatLosesSightBehindAColumnIsMovedToSeeIt) {
  const ReconfigurationConfig config = HiddenObjectConfig();
  const ReconfigurationResult r = RunReconfiguration(config);
  EXPECT_EQ(r.frames.front().visibility[kTruePoses][0].area, 0.0);  // hidden at home
  const ReconfigurationFrame& last = r.frames.back();
  EXPECT_EQ(last.visibility[kFixedCameras][0].area, 0.0);
  EXPECT_GE(last.visibility[kTruePoses][0].area, 0.99);
  EXPECT_GT(std::abs(last.states[kTruePoses][0].rail_m), 0.1);   // moved sideways ...
  EXPECT_GT(std::abs(last.states[kTruePoses][0].pan_rad), 0.1);  // ... and turned to it
  EXPECT_EQ(r.frames_seen_by_fewer[kFixedCameras], config.frames);
  EXPECT_LT(r.frames_seen_by_fewer[kTruePoses], config.frames / 2);
}

TEST(CameraReconfiguration, PlannerAssignsTheMBestCameras) {
  // Three cameras on rotary stages only: one behind a column, one far away, one close.
  std::vector<CameraAgent> agents;
  for (const Eigen::Vector2d& position :
       {Eigen::Vector2d(0.0, -1.0), Eigen::Vector2d(-1.4, 0.0), Eigen::Vector2d(0.9, 0.0)}) {
    StageCamera c = RailCamera();
    c.rail_min_m = c.rail_max_m = 0.0;
    c.rail_origin_m = position;
    c.pan_zero_rad = std::atan2(-position.x(), -position.y());  // looking at the origin
    c.focus_distance_m = 0.9;
    agents.emplace_back(c);
  }
  std::vector<int> current;
  for (const CameraAgent& a : agents) current.push_back(a.NearestPose(a.camera().home));
  const std::vector<Column> columns = {{{0.0, -0.5}, 0.06}};
  const std::vector<BoundingEllipse> predicted(3, ObjectAt(0.0, 0.0));
  PlannerOptions options;
  options.assigned_cameras = 2;
  CameraPlans plans =
      PlanCameras(agents, current, predicted, columns, 0.2, VisibilityOptions(), options);
  ASSERT_EQ(plans.cameras.size(), 3u);
  EXPECT_EQ(plans.lookahead, 3);
  EXPECT_FALSE(plans.cameras[0].assigned);
  EXPECT_TRUE(plans.cameras[1].assigned);
  EXPECT_TRUE(plans.cameras[2].assigned);
  EXPECT_GT(plans.cameras[2].best_visibility, plans.cameras[1].best_visibility);
  EXPECT_GT(plans.cameras[1].best_visibility, plans.cameras[0].best_visibility);
  options.assigned_cameras = 1;
  plans = PlanCameras(agents, current, predicted, columns, 0.2, VisibilityOptions(), options);
  EXPECT_FALSE(plans.cameras[1].assigned);
  EXPECT_TRUE(plans.cameras[2].assigned);
  options.min_visibility = 1.0;  // nobody reaches it
  plans = PlanCameras(agents, current, predicted, columns, 0.2, VisibilityOptions(), options);
  for (const CameraPlan& p : plans.cameras) EXPECT_FALSE(p.assigned);
}

TEST(CameraReconfiguration, UnassignedCameraIsPrePositionedForLaterInstants) {
  StageCamera c = RailCamera();
  c.rail_min_m = c.rail_max_m = 0.0;
  const std::vector<CameraAgent> agents = {CameraAgent(c)};
  const std::vector<int> current = {agents[0].NearestPose(c.home)};
  // Straight ahead at t1, then 30 deg to the right from t2 on.
  std::vector<BoundingEllipse> predicted = {ObjectAt(0.0, -0.2)};
  for (int l = 0; l < 4; ++l)
    predicted.push_back(ObjectAt(0.8 * std::sin(30 * kDeg), -1.0 + 0.8 * std::cos(30 * kDeg)));
  PlannerOptions options;
  options.min_visibility = 1.0;  // unassigned
  options.max_lookahead = 1;
  const double near = PlanCameras(agents, current, predicted, {}, 0.2, VisibilityOptions(), options)
                          .cameras[0]
                          .target.pan_rad;
  EXPECT_NEAR(near, 0.0, 1e-12);  // t1 alone: stays on the object
  options.max_lookahead = 5;
  const CameraPlans ahead =
      PlanCameras(agents, current, predicted, {}, 0.2, VisibilityOptions(), options);
  EXPECT_EQ(ahead.lookahead, 5);
  EXPECT_NEAR(ahead.cameras[0].target.pan_rad, 8 * kDeg, 1e-9);  // as far as it can turn
}

TEST(CameraReconfiguration, TrackedPoseVisibilityIsCloseToTruth) {
  ReconfigurationConfig config = LoadReconfigurationConfig(std::string(UNSEEN_SOURCE_DIR) +
                                                           "/configs/apps/reconfiguration.yaml");
  ASSERT_EQ(config.cameras.size(), 3u);
  ASSERT_EQ(config.columns.size(), 2u);
  EXPECT_EQ(config.tracking_cameras, 5);
  EXPECT_EQ(config.planner.assigned_cameras, 2);
  EXPECT_NEAR(config.cameras[0].horizontal_fov_rad, 24 * kDeg, 1e-12);
  config.frames = 36;
  config.tracking_cameras = 2;  // a shorter test
  const ReconfigurationResult r = RunReconfiguration(config);
  EXPECT_EQ(r.lost_frames, 0);
  EXPECT_LT(r.max_position_error_m, 0.016);  // the thesis's 16 mm
  EXPECT_NEAR(r.mean_visibility[kTrackedPoses], r.mean_visibility[kTruePoses], 0.02);
  EXPECT_LT(r.max_tracked_excess, 0.05);
  EXPECT_GT(r.mean_visibility[kTruePoses], r.mean_visibility[kFixedCameras] + 0.05);
}

TEST(CameraReconfiguration, ConfigErrorsNameTheProblem) {
  ReconfigurationConfig config = HiddenObjectConfig();
  config.cameras[0].home.rail_m = 2.0;  // beyond the rail
  EXPECT_THROW(RunReconfiguration(config), Error);
  config = HiddenObjectConfig();
  config.planner.assigned_cameras = 0;
  EXPECT_THROW(config.Check(), Error);
  EXPECT_THROW(LoadReconfigurationConfig("/nonexistent/reconfiguration.yaml"), Error);
}

}  // namespace
}  // namespace unseen
