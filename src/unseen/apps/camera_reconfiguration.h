// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Dynamic camera reconfiguration (SPEC 7.2, thesis 5.3): cameras on rotary and linear stages
// are moved so that the tracked object stays visible among column obstacles, by the
// visibility (5.1) of predicted object poses. Each camera has an agent that ranks its
// feasible poses F_i (the stage grid within the limits) that are achievable A_i (within the
// actuator speeds) for every demand instant; a central planner assigns the M cameras of
// highest visibility to the object and pre-positions the others for later instants, looking
// further ahead (instants t1, then t1..t2, ...) while its time budget t_max allows.
//
// The simulation reproduces the thesis set-up in the top view (visibility.h): 3
// reconfigurable cameras (24 deg), 2 columns, and the 5 stationary tracking cameras (34 deg,
// SPEC 8's rig of five 512x256 cameras on a line) whose rendered images the tracker tracks
// the object in; the reconfiguration runs on the tracked poses, on the true poses (the
// thesis's "ideal tracking") and is compared with cameras left at their default poses.
#pragma once

#include <Eigen/Core>
#include <array>
#include <span>
#include <string>
#include <vector>

#include "unseen/apps/visibility.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/io/pose_stream.h"

namespace unseen {

// Where a camera's stages stand: the linear stage's position and the rotary stage's angle.
struct StageState {
  double rail_m = 0.0;
  double pan_rad = 0.0;
};

// A reconfigurable camera: a rotary stage (its axis through the optical centre), optionally
// carried by a linear stage (rail), in the top view.
struct StageCamera {
  std::string name = "camera";
  Eigen::Vector2d rail_origin_m = Eigen::Vector2d::Zero();    // optical centre at rail 0
  Eigen::Vector2d rail_direction = Eigen::Vector2d::UnitX();  // the rail's axis (normalised)
  double rail_min_m = 0.0, rail_max_m = 0.0;     // linear-stage limits; equal: no linear stage
  double rail_speed_m_s = 0.2;                   // linear actuator speed
  double rail_step_m = 0.02;                     // spacing of the feasible rail positions
  double pan_zero_rad = 0.0;                     // heading at pan 0
  double pan_min_rad = -0.7, pan_max_rad = 0.7;  // rotary-stage limits, relative to pan 0
  double pan_speed_rad_s = 0.7;                  // rotary actuator speed
  double pan_step_rad = 0.01745;                 // spacing of the feasible pan angles (1 deg)
  StageState home;                               // the default pose
  double horizontal_fov_rad = 0.4189;            // 24 deg
  double focus_distance_m = 0.9;                 // distance of the point in focus, (5.1)
  void Check() const;
  TopViewCamera ViewAt(const StageState& state) const;
};

// A feasible pose of a camera and its visibility.
struct RankedPose {
  int index = 0;
  double visibility = 0.0;
};

// The agent of one camera: its feasible poses F_i, a grid over the stage limits, and which
// of them are achievable A_i from a pose within a time (each stage at its actuator speed).
class CameraAgent {
 public:
  explicit CameraAgent(StageCamera camera);  // throws for a camera failing Check()

  const StageCamera& camera() const { return camera_; }
  int num_poses() const { return num_rail_ * num_pan_; }
  StageState Pose(int index) const;
  // The feasible pose closest to `state` (clamped to the limits).
  int NearestPose(const StageState& state) const;
  // Grid steps (rail, pan) each stage can move in `dt_s` seconds.
  std::array<int, 2> ReachSteps(double dt_s) const;
  bool Reachable(int from, int to, double dt_s) const;
  // The visibility of `ellipse` from every feasible pose within `steps` (rail, pan) grid steps
  // of `from` (A_i for those steps), -1 elsewhere.
  std::vector<double> Evaluate(int from, const std::array<int, 2>& steps,
                               const BoundingEllipse& ellipse, std::span<const Column> columns,
                               const VisibilityOptions& options) const;
  // For every pose, the largest of `values` (one per pose, < 0: not evaluated) over the
  // poses within `steps` (rail, pan) grid steps; -1 where none.
  std::vector<double> BestWithin(const std::vector<double>& values,
                                 const std::array<int, 2>& steps) const;
  // The poses achievable from `from` within `dt_s`, best visibility first (ties: the
  // smaller move first).
  std::vector<RankedPose> Rank(int from, double dt_s, const BoundingEllipse& ellipse,
                               std::span<const Column> columns,
                               const VisibilityOptions& options) const;

 private:
  int RailIndex(int index) const { return index / num_pan_; }
  int PanIndex(int index) const { return index % num_pan_; }
  StageCamera camera_;
  int num_rail_ = 1, num_pan_ = 1;
};

struct PlannerOptions {
  int assigned_cameras = 2;     // M: cameras assigned to the object
  double min_visibility = 0.5;  // V_min: a camera below it at all its poses is unassigned
  int max_lookahead = 5;        // m: demand instants looked ahead at most
  // Weight of instant l in the performance function Pr: decay^(l-1), near instants count
  // most as the prediction's uncertainty grows with its span.
  double lookahead_decay = 0.7;
  // t_max: processing time after which no further instant is added, ms; 0: always
  // max_lookahead (deterministic).
  double time_budget_ms = 0.0;
  void Check() const;
};

struct CameraPlan {
  int pose_index = 0;  // the feasible pose to be at by demand instant t1
  StageState target;
  bool assigned = false;         // one of the M cameras given to the object at t1
  double best_visibility = 0.0;  // the best V at t1 over the achievable poses
  double visibility = 0.0;       // V at t1 of the chosen pose
};

struct CameraPlans {
  std::vector<CameraPlan> cameras;
  int lookahead = 0;  // demand instants the plan looked at
};

// The central planner. `current[i]`: camera i's feasible pose now; `predicted[l]`: the
// object at demand instant t_{l+1}, `interval_s` apart (at least one). Rules (5.3.1):
// cameras whose best achievable V at t1 is below V_min are unassigned; of the others the M
// of highest V are assigned; assigned cameras go to the pose of best weighted visibility
// sum over t1..t_m, unassigned ones are pre-positioned for t2..t_m (t1 alone when m = 1).
CameraPlans PlanCameras(std::span<const CameraAgent> agents, std::span<const int> current,
                        std::span<const BoundingEllipse> predicted, std::span<const Column> columns,
                        double interval_s, const VisibilityOptions& visibility,
                        const PlannerOptions& options);

// The object's top-view ellipse at `world_from_obj`: the ellipse of least area around its
// footprint box, a square of `edge_m` (semi-axes edge / sqrt 2), turned by its yaw.
BoundingEllipse ObjectEllipse(const Rigid3d& world_from_obj, double edge_m);

// The simulated scene and run.
struct ReconfigurationConfig {
  double fps = 30.0;
  int frames = 240;
  int demand_interval_frames = 6;  // frames between demand instants
  int velocity_window_frames = 6;  // constant-velocity prediction over this many frames
  double min_seen_share = 0.5;     // a camera sees the object: area term at least this
  bool track = true;  // false: the planner's "tracked" poses are the true ones (no tracker)
  // The object: the lettered cube on an x-y-theta stage, top-view waypoints at constant
  // speed, spinning about the vertical.
  double object_edge_m = 0.096;
  std::vector<Eigen::Vector2d> path_m;  // top-view waypoints, the first the start
  double path_speed_m_s = 0.067;
  double spin_rad_s = 0.18;
  double start_heading_rad = 0.5;
  // The tracking rig: `tracking_cameras` 512x256 cameras (fx = fy = 837.3) looking along
  // +z, on the line z = 0 from x = tracking_from_x_m to tracking_to_x_m.
  int tracking_cameras = 5;
  double tracking_from_x_m = -0.1, tracking_to_x_m = 0.1;
  std::vector<Column> columns;
  std::vector<StageCamera> cameras;
  VisibilityOptions visibility;
  PlannerOptions planner;
  void Check() const;
};

// Reads a configuration (configs/apps/reconfiguration.yaml documents the keys; angles in
// degrees there). Throws naming the file and key.
ReconfigurationConfig LoadReconfigurationConfig(const std::string& path);

// The three camera set-ups compared.
enum Variant { kTrackedPoses = 0, kTruePoses = 1, kFixedCameras = 2, kNumVariants = 3 };
const char* VariantName(int variant);  // "tracked", "truth", "fixed"

struct ReconfigurationFrame {
  Rigid3d true_world_from_obj, tracked_world_from_obj;
  TrackStatus status = TrackStatus::kTracking;
  // [variant][camera]: the stages and the visibility (5.1) of the true object.
  std::array<std::vector<StageState>, kNumVariants> states;
  std::array<std::vector<VisibilityTerms>, kNumVariants> visibility;
  std::array<std::vector<bool>, kNumVariants> assigned;  // at the last demand instant
};

struct ReconfigurationResult {
  std::vector<ReconfigurationFrame> frames;
  std::array<double, kNumVariants> mean_visibility{};  // over frames and cameras
  std::array<std::vector<double>, kNumVariants> camera_mean_visibility;
  std::array<int, kNumVariants> frames_seen_by_fewer{};  // seen by fewer than M cameras
  // Frames where the tracked run's visibility (mean over cameras) is at most 0.02 above the
  // true run's, i.e. equal to or below it (the thesis's statement), and the largest excess.
  int frames_tracked_not_above = 0;
  double max_tracked_excess = 0.0;
  int lost_frames = 0;
  double mean_position_error_m = 0.0, max_position_error_m = 0.0;
  double mean_lookahead = 0.0;  // demand instants looked at per plan
  int plans = 0;
  double synth_s = 0.0, track_s = 0.0, plan_s = 0.0, total_s = 0.0;  // wall clock
  double Fps() const { return total_s > 0 ? frames.size() / total_s : 0.0; }
  // Without rendering the tracking cameras' images (a real rig delivers them).
  double FpsWithoutSynthesis() const {
    return total_s - synth_s > 0 ? frames.size() / (total_s - synth_s) : 0.0;
  }
};

// The object's true pose at frame `frame` (top-view path at y = 0, yaw spin).
Rigid3d TrueObjectPose(const ReconfigurationConfig& config, int frame);

// Runs the simulation: every frame renders the tracking cameras' images and tracks the
// object (when config.track), plans the reconfigurable cameras at every demand instant for
// the tracked and the true poses, moves them at their actuator speeds and scores the
// visibility of the true object for the three variants.
ReconfigurationResult RunReconfiguration(const ReconfigurationConfig& config);

}  // namespace unseen
