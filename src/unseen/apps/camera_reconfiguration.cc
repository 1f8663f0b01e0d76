// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/apps/camera_reconfiguration.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "unseen/camera/camera.h"
#include "unseen/mesh/primitives.h"
#include "unseen/render/rasterizer.h"
#include "unseen/track/tracker.h"
#include "unseen/util/error.h"
#include "unseen/util/timer.h"
#include "unseen/util/yaml_options.h"

namespace unseen {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

int GridSize(double min, double max, double step) {
  return max > min ? static_cast<int>(std::floor((max - min) / step + 1e-9)) + 1 : 1;
}

// Angle wrapped to (-pi, pi].
double WrapAngle(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

double Yaw(const Rigid3d& world_from_obj) {
  const Eigen::Vector3d z = world_from_obj.rotation() * Eigen::Vector3d::UnitZ();
  return std::atan2(z.x(), z.z());
}

// One step of a stage towards `target` at `max_step`.
double StepTowards(double value, double target, double max_step) {
  return value + std::clamp(target - value, -max_step, max_step);
}

// The largest of `in`, a row-major num_outer x num_inner grid (< 0: none), within `steps`
// entries along the outer axis or the inner one.
std::vector<double> SlidingMax(const std::vector<double>& in, int num_outer, int num_inner,
                               int steps, bool along_outer) {
  std::vector<double> out(in.size(), -1.0);
  const int n = along_outer ? num_outer : num_inner;
  const int stride = along_outer ? num_inner : 1;
  for (int o = 0; o < num_outer; ++o) {
    for (int i = 0; i < num_inner; ++i) {
      const int at = along_outer ? o : i;
      const int base = o * num_inner + i - at * stride;
      double best = -1.0;
      for (int q = std::max(0, at - steps); q <= std::min(n - 1, at + steps); ++q) {
        best = std::max(best, in[base + q * stride]);
      }
      out[o * num_inner + i] = best;
    }
  }
  return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Stages and agents

void StageCamera::Check() const {
  UNSEEN_CHECK(rail_direction.norm() > 1e-9, "camera {}: rail_direction must be non-zero", name);
  UNSEEN_CHECK(rail_min_m <= rail_max_m && home.rail_m >= rail_min_m && home.rail_m <= rail_max_m,
               "camera {}: rail limits [{}, {}] m must hold the home position {} m", name,
               rail_min_m, rail_max_m, home.rail_m);
  UNSEEN_CHECK(
      pan_min_rad <= pan_max_rad && home.pan_rad >= pan_min_rad && home.pan_rad <= pan_max_rad,
      "camera {}: pan limits [{}, {}] rad must hold the home angle {} rad", name, pan_min_rad,
      pan_max_rad, home.pan_rad);
  UNSEEN_CHECK(rail_step_m > 0 && pan_step_rad > 0,
               "camera {}: rail_step_m ({}) and pan_step_rad ({}) must be > 0", name, rail_step_m,
               pan_step_rad);
  UNSEEN_CHECK(rail_speed_m_s >= 0 && pan_speed_rad_s >= 0,
               "camera {}: actuator speeds must be >= 0 (rail {} m/s, pan {} rad/s)", name,
               rail_speed_m_s, pan_speed_rad_s);
  UNSEEN_CHECK(horizontal_fov_rad > 0 && horizontal_fov_rad < std::numbers::pi,
               "camera {}: horizontal_fov_rad must be in (0, pi), not {}", name,
               horizontal_fov_rad);
  UNSEEN_CHECK(focus_distance_m > 0, "camera {}: focus_distance_m must be > 0, not {}", name,
               focus_distance_m);
}

TopViewCamera StageCamera::ViewAt(const StageState& state) const {
  TopViewCamera view;
  view.position_m = rail_origin_m + state.rail_m * rail_direction.normalized();
  view.heading_rad = pan_zero_rad + state.pan_rad;
  view.horizontal_fov_rad = horizontal_fov_rad;
  view.focus_distance_m = focus_distance_m;
  return view;
}

CameraAgent::CameraAgent(StageCamera camera) : camera_(std::move(camera)) {
  camera_.Check();
  num_rail_ = GridSize(camera_.rail_min_m, camera_.rail_max_m, camera_.rail_step_m);
  num_pan_ = GridSize(camera_.pan_min_rad, camera_.pan_max_rad, camera_.pan_step_rad);
}

StageState CameraAgent::Pose(int index) const {
  return {camera_.rail_min_m + RailIndex(index) * camera_.rail_step_m,
          camera_.pan_min_rad + PanIndex(index) * camera_.pan_step_rad};
}

int CameraAgent::NearestPose(const StageState& state) const {
  const int r = std::clamp(
      static_cast<int>(std::lround((state.rail_m - camera_.rail_min_m) / camera_.rail_step_m)), 0,
      num_rail_ - 1);
  const int p = std::clamp(
      static_cast<int>(std::lround((state.pan_rad - camera_.pan_min_rad) / camera_.pan_step_rad)),
      0, num_pan_ - 1);
  return r * num_pan_ + p;
}

std::array<int, 2> CameraAgent::ReachSteps(double dt_s) const {
  return {
      static_cast<int>(std::floor(camera_.rail_speed_m_s * dt_s / camera_.rail_step_m + 1e-9)),
      static_cast<int>(std::floor(camera_.pan_speed_rad_s * dt_s / camera_.pan_step_rad + 1e-9))};
}

bool CameraAgent::Reachable(int from, int to, double dt_s) const {
  const std::array<int, 2> steps = ReachSteps(dt_s);
  return std::abs(RailIndex(to) - RailIndex(from)) <= steps[0] &&
         std::abs(PanIndex(to) - PanIndex(from)) <= steps[1];
}

std::vector<double> CameraAgent::Evaluate(int from, const std::array<int, 2>& steps,
                                          const BoundingEllipse& ellipse,
                                          std::span<const Column> columns,
                                          const VisibilityOptions& options) const {
  std::vector<double> v(num_poses(), -1.0);
  const int r0 = RailIndex(from), p0 = PanIndex(from);
  for (int r = std::max(0, r0 - steps[0]); r <= std::min(num_rail_ - 1, r0 + steps[0]); ++r) {
    for (int p = std::max(0, p0 - steps[1]); p <= std::min(num_pan_ - 1, p0 + steps[1]); ++p) {
      const int index = r * num_pan_ + p;
      v[index] = Visibility(camera_.ViewAt(Pose(index)), ellipse, columns, options).value;
    }
  }
  return v;
}

std::vector<double> CameraAgent::BestWithin(const std::vector<double>& values,
                                            const std::array<int, 2>& steps) const {
  UNSEEN_CHECK(static_cast<int>(values.size()) == num_poses(),
               "CameraAgent::BestWithin: {} values for {} poses", values.size(), num_poses());
  // Separable: the maximum along the pan axis, then along the rail.
  return SlidingMax(SlidingMax(values, num_rail_, num_pan_, steps[1], false), num_rail_, num_pan_,
                    steps[0], true);
}

std::vector<RankedPose> CameraAgent::Rank(int from, double dt_s, const BoundingEllipse& ellipse,
                                          std::span<const Column> columns,
                                          const VisibilityOptions& options) const {
  const std::vector<double> v = Evaluate(from, ReachSteps(dt_s), ellipse, columns, options);
  std::vector<RankedPose> ranked;
  for (int i = 0; i < num_poses(); ++i) {
    if (v[i] >= 0) ranked.push_back({i, v[i]});
  }
  const auto move = [&](int i) {
    return std::abs(RailIndex(i) - RailIndex(from)) + std::abs(PanIndex(i) - PanIndex(from));
  };
  std::sort(ranked.begin(), ranked.end(), [&](const RankedPose& a, const RankedPose& b) {
    if (a.visibility != b.visibility) return a.visibility > b.visibility;
    return move(a.index) < move(b.index);
  });
  return ranked;
}

// ---------------------------------------------------------------------------------------
// The central planner

void PlannerOptions::Check() const {
  UNSEEN_CHECK(assigned_cameras >= 1, "planner: assigned_cameras (M) must be >= 1, not {}",
               assigned_cameras);
  UNSEEN_CHECK(min_visibility >= 0 && min_visibility <= 1,
               "planner: min_visibility must be in [0, 1], not {}", min_visibility);
  UNSEEN_CHECK(max_lookahead >= 1, "planner: max_lookahead must be >= 1, not {}", max_lookahead);
  UNSEEN_CHECK(lookahead_decay > 0 && lookahead_decay <= 1,
               "planner: lookahead_decay must be in (0, 1], not {}", lookahead_decay);
  UNSEEN_CHECK(time_budget_ms >= 0, "planner: time_budget_ms must be >= 0, not {}", time_budget_ms);
}

CameraPlans PlanCameras(std::span<const CameraAgent> agents, std::span<const int> current,
                        std::span<const BoundingEllipse> predicted, std::span<const Column> columns,
                        double interval_s, const VisibilityOptions& visibility,
                        const PlannerOptions& options) {
  UNSEEN_CHECK(agents.size() == current.size() && !predicted.empty() && interval_s > 0,
               "PlanCameras: {} agents, {} current poses, {} demand instants, interval {} s",
               agents.size(), current.size(), predicted.size(), interval_s);
  const Timer timer;
  const int n = static_cast<int>(agents.size());
  const int max_instants = std::min<int>(options.max_lookahead, predicted.size());
  // values[i][l]: camera i's visibility at instant l+1 over the poses it can reach by then.
  std::vector<std::vector<std::vector<double>>> values(n);
  int instants = 0;
  while (instants < max_instants) {
    for (int i = 0; i < n; ++i) {
      std::array<int, 2> steps = agents[i].ReachSteps(interval_s);
      for (int& s : steps) s *= instants + 1;
      values[i].push_back(
          agents[i].Evaluate(current[i], steps, predicted[instants], columns, visibility));
    }
    ++instants;
    if (options.time_budget_ms > 0 && timer.ElapsedMilliseconds() >= options.time_budget_ms) break;
  }

  CameraPlans plans;
  plans.lookahead = instants;
  plans.cameras.resize(n);
  // Assignment at t1: the M cameras of highest achievable V, if at least V_min.
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) {
    order[i] = i;
    plans.cameras[i].best_visibility = *std::max_element(values[i][0].begin(), values[i][0].end());
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return plans.cameras[a].best_visibility > plans.cameras[b].best_visibility;
  });
  for (int k = 0; k < std::min(n, options.assigned_cameras); ++k) {
    CameraPlan& plan = plans.cameras[order[k]];
    plan.assigned = plan.best_visibility >= options.min_visibility;
  }

  for (int i = 0; i < n; ++i) {
    const CameraAgent& agent = agents[i];
    const std::array<int, 2> reach = agent.ReachSteps(interval_s);
    // Backward over the instants: future[p] = the best weighted visibility sum over
    // t_{l+1}..t_m from pose p at t_l, moving at most `reach` grid steps per interval (Pr).
    std::vector<double> future(agent.num_poses(), 0.0);
    for (int l = instants - 1; l >= 1; --l) {
      const double weight = std::pow(options.lookahead_decay, l);
      std::vector<double> total = values[i][l];
      for (int q = 0; q < agent.num_poses(); ++q) {
        if (total[q] >= 0) total[q] = weight * total[q] + future[q];
      }
      future = agent.BestWithin(total, reach);
    }
    // Assigned cameras: V(t1) plus the look-ahead; unassigned ones are pre-positioned for
    // the later instants (t1 alone when there are none). Ties: the smaller move.
    CameraPlan& plan = plans.cameras[i];
    const bool pre_position = !plan.assigned && instants > 1;
    const std::vector<double>& v1 = values[i][0];
    const StageState now = agent.Pose(current[i]);
    double best = -std::numeric_limits<double>::infinity();
    for (int p = 0; p < agent.num_poses(); ++p) {
      if (v1[p] < 0) continue;
      const StageState s = agent.Pose(p);
      const double move = std::abs(s.rail_m - now.rail_m) + std::abs(s.pan_rad - now.pan_rad);
      const double score = (pre_position ? 0.0 : v1[p]) + future[p] - 1e-9 * move;
      if (score > best) {
        best = score;
        plan.pose_index = p;
        plan.visibility = v1[p];
      }
    }
    plan.target = agent.Pose(plan.pose_index);
  }
  return plans;
}

BoundingEllipse ObjectEllipse(const Rigid3d& world_from_obj, double edge_m) {
  BoundingEllipse e;
  e.centre_m = {world_from_obj.translation().x(), world_from_obj.translation().z()};
  e.semi_axes_m = Eigen::Vector2d::Constant(edge_m / std::numbers::sqrt2);
  e.heading_rad = Yaw(world_from_obj);
  return e;
}

// ---------------------------------------------------------------------------------------
// Configuration

void ReconfigurationConfig::Check() const {
  UNSEEN_CHECK(fps > 0 && frames >= 1, "reconfiguration: fps ({}) and frames ({}) must be > 0", fps,
               frames);
  UNSEEN_CHECK(demand_interval_frames >= 1 && velocity_window_frames >= 1,
               "reconfiguration: demand_interval_frames ({}) and velocity_window_frames ({}) "
               "must be >= 1",
               demand_interval_frames, velocity_window_frames);
  UNSEEN_CHECK(min_seen_share > 0 && min_seen_share <= 1,
               "reconfiguration: min_seen_share must be in (0, 1], not {}", min_seen_share);
  UNSEEN_CHECK(object_edge_m > 0 && path_speed_m_s >= 0 && !path_m.empty(),
               "reconfiguration: the object needs edge_m > 0 ({}), speed_m_s >= 0 ({}) and a "
               "path of at least one point",
               object_edge_m, path_speed_m_s);
  UNSEEN_CHECK(tracking_cameras >= 1, "reconfiguration: tracking_cameras must be >= 1, not {}",
               tracking_cameras);
  UNSEEN_CHECK(!cameras.empty(), "reconfiguration: no reconfigurable camera");
  for (const Column& c : columns) {
    UNSEEN_CHECK(c.radius_m > 0, "reconfiguration: a column's radius_m must be > 0, not {}",
                 c.radius_m);
  }
  for (const StageCamera& c : cameras) c.Check();
  visibility.Check();
  planner.Check();
}

namespace {

YamlSetter YamlPoint(Eigen::Vector2d* point) {
  return [point](const YAML::Node& node, const std::string& where) {
    std::vector<double> xz;
    YamlField (&xz)(node, where);
    UNSEEN_CHECK(xz.size() == 2, "{}: expected a top-view point [x, z], got {} numbers", where,
                 xz.size());
    *point = {xz[0], xz[1]};
  };
}

YamlSetter YamlPath(std::vector<Eigen::Vector2d>* path) {
  return [path](const YAML::Node& node, const std::string& where) {
    UNSEEN_CHECK(node.IsSequence(), "{}: expected a list of [x, z] points", where);
    path->assign(node.size(), Eigen::Vector2d::Zero());
    for (size_t i = 0; i < node.size(); ++i) {
      YamlPoint (&(*path)[i])(node[i], fmt::format("{}[{}]", where, i));
    }
  };
}

YamlSection CameraFields(StageCamera* c) {
  return {{"name", YamlField(&c->name)},
          {"position_m", YamlPoint(&c->rail_origin_m)},
          {"rail_direction", YamlPoint(&c->rail_direction)},
          {"rail_min_m", YamlField(&c->rail_min_m)},
          {"rail_max_m", YamlField(&c->rail_max_m)},
          {"rail_speed_m_s", YamlField(&c->rail_speed_m_s)},
          {"rail_step_m", YamlField(&c->rail_step_m)},
          {"home_rail_m", YamlField(&c->home.rail_m)},
          {"heading_deg", YamlScaledField(&c->pan_zero_rad, kDeg)},
          {"pan_min_deg", YamlScaledField(&c->pan_min_rad, kDeg)},
          {"pan_max_deg", YamlScaledField(&c->pan_max_rad, kDeg)},
          {"pan_speed_deg_s", YamlScaledField(&c->pan_speed_rad_s, kDeg)},
          {"pan_step_deg", YamlScaledField(&c->pan_step_rad, kDeg)},
          {"home_pan_deg", YamlScaledField(&c->home.pan_rad, kDeg)},
          {"horizontal_fov_deg", YamlScaledField(&c->horizontal_fov_rad, kDeg)},
          {"focus_distance_m", YamlField(&c->focus_distance_m)}};
}

// Reads a list section of `root` (then removed from it) with one map per entry.
template <typename T>
void ReadList(YAML::Node& root, const std::string& key, const std::string& what,
              YamlSection (*fields)(T*), std::vector<T>* out) {
  if (!root.IsMap() || !root[key]) return;
  const YAML::Node list = root[key];
  UNSEEN_CHECK(list.IsSequence(), "{}: {} must be a list", what, key);
  out->assign(list.size(), T());
  for (size_t i = 0; i < list.size(); ++i) {
    ApplyYamlSection(list[i], fmt::format("{}: {}[{}]", what, key, i), fields(&(*out)[i]));
  }
  root.remove(key);
}

YamlSection ColumnFields(Column* c) {
  return {{"centre_m", YamlPoint(&c->centre_m)}, {"radius_m", YamlField(&c->radius_m)}};
}

}  // namespace

ReconfigurationConfig LoadReconfigurationConfig(const std::string& path) {
  YAML::Node root = YAML::Clone(LoadYamlFile(path, "reconfiguration config"));
  ReconfigurationConfig c;
  ReadList(root, "columns", path, &ColumnFields, &c.columns);
  ReadList(root, "cameras", path, &CameraFields, &c.cameras);
  VisibilityOptions& v = c.visibility;
  PlannerOptions& p = c.planner;
  const std::map<std::string, YamlSection> sections = {
      {"simulation",
       {{"fps", YamlField(&c.fps)},
        {"frames", YamlField(&c.frames)},
        {"demand_interval_frames", YamlField(&c.demand_interval_frames)},
        {"velocity_window_frames", YamlField(&c.velocity_window_frames)},
        {"min_seen_share", YamlField(&c.min_seen_share)},
        {"track", YamlField(&c.track)}}},
      {"object",
       {{"edge_m", YamlField(&c.object_edge_m)},
        {"path_m", YamlPath(&c.path_m)},
        {"speed_m_s", YamlField(&c.path_speed_m_s)},
        {"spin_deg_s", YamlScaledField(&c.spin_rad_s, kDeg)},
        {"start_heading_deg", YamlScaledField(&c.start_heading_rad, kDeg)}}},
      {"tracking_rig",
       {{"cameras", YamlField(&c.tracking_cameras)},
        {"from_x_m", YamlField(&c.tracking_from_x_m)},
        {"to_x_m", YamlField(&c.tracking_to_x_m)}}},
      {"visibility",
       {{"area_weight", YamlField(&v.area_weight)},
        {"distance_weight", YamlField(&v.distance_weight)},
        {"angle_weight", YamlField(&v.angle_weight)},
        {"max_distance_m", YamlField(&v.max_distance_m)},
        {"max_angle_deg", YamlScaledField(&v.max_angle_rad, kDeg)}}},
      {"planner",
       {{"assigned_cameras", YamlField(&p.assigned_cameras)},
        {"min_visibility", YamlField(&p.min_visibility)},
        {"max_lookahead", YamlField(&p.max_lookahead)},
        {"lookahead_decay", YamlField(&p.lookahead_decay)},
        {"time_budget_ms", YamlField(&p.time_budget_ms)}}},
  };
  ApplyYamlSections(root, path, sections);
  c.Check();
  return c;
}

const char* VariantName(int variant) {
  static const char* const kNames[] = {"tracked", "truth", "fixed"};
  UNSEEN_CHECK(variant >= 0 && variant < kNumVariants, "VariantName: no variant {}", variant);
  return kNames[variant];
}

// ---------------------------------------------------------------------------------------
// The simulation

Rigid3d TrueObjectPose(const ReconfigurationConfig& config, int frame) {
  const double t = frame / config.fps;
  double along = config.path_speed_m_s * t;
  Eigen::Vector2d p = config.path_m.front();
  for (size_t i = 1; i < config.path_m.size(); ++i) {
    const Eigen::Vector2d leg = config.path_m[i] - config.path_m[i - 1];
    const double len = leg.norm();
    if (along <= len) {
      p = config.path_m[i - 1] + (len > 0 ? along / len : 0.0) * leg;
      along = -1.0;
      break;
    }
    along -= len;
    p = config.path_m[i];
  }
  const double yaw = config.start_heading_rad + config.spin_rad_s * t;
  return Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY())),
                 Eigen::Vector3d(p.x(), 0.0, p.y()));
}

namespace {

// The stationary tracking rig and the images it sees (the object over a smooth
// background, rendered 2x2 supersampled within the object's rectangle only).
class TrackingRig {
 public:
  explicit TrackingRig(const ReconfigurationConfig& config)
      : model_(MakeLetteredCube(config.object_edge_m)) {
    const int n = config.tracking_cameras;
    for (int i = 0; i < n; ++i) {
      const double x = n == 1
                           ? 0.5 * (config.tracking_from_x_m + config.tracking_to_x_m)
                           : config.tracking_from_x_m +
                                 i * (config.tracking_to_x_m - config.tracking_from_x_m) / (n - 1);
      rig_.cameras.push_back({fmt::format("track{}", i), PinholeCamera::Centered(512, 256, 837.3),
                              Rigid3d(Eigen::Quaterniond::Identity(), {x, 0.0, 0.0})});
      cv::RNG rng(1000 + i);
      cv::Mat coarse(9, 17, CV_32FC3);
      rng.fill(coarse, cv::RNG::UNIFORM, 0.3, 0.8);
      cv::Mat background;
      cv::resize(coarse, background, cv::Size(512, 256), 0, 0, cv::INTER_CUBIC);
      backgrounds_.push_back(background);
    }
    Eigen::Vector3f centre;
    model_.BoundingSphere(&centre, &radius_);
  }

  const Rig& rig() const { return rig_; }
  const Mesh& model() const { return model_; }

  std::vector<cv::Mat> Images(const Rigid3d& world_from_obj) {
    std::vector<cv::Mat> images;
    for (int i = 0; i < rig_.size(); ++i) {
      const RigCamera& cam = rig_.cameras[i];
      const PinholeCamera fine = cam.intrinsics.Scaled(0.5);
      const Rigid3d cam_from_obj = cam.cam_from_world() * world_from_obj;
      cv::Mat image = backgrounds_[i].clone();
      const auto rect = fine.SphereRect(cam_from_obj.translation(), radius_);
      if (rect) {
        // An even-aligned rectangle at the fine resolution: whole coarse pixels.
        PixelRect r = rect->Grow(2);
        r = {r.x0 & ~1, r.y0 & ~1, (r.x1 + 1) & ~1, (r.y1 + 1) & ~1};
        r = r.Intersect(fine.ImageRect());
        Render(model_, fine, cam_from_obj, r, RenderOptions(), &buffers_);
        const cv::Rect coarse(r.x0 / 2, r.y0 / 2, r.width() / 2, r.height() / 2);
        cv::Mat patch;
        cv::resize(backgrounds_[i](coarse), patch, buffers_.color.size(), 0, 0, cv::INTER_LINEAR);
        buffers_.color.copyTo(patch, buffers_.mask);
        cv::resize(patch, image(coarse), coarse.size(), 0, 0, cv::INTER_AREA);
      }
      images.push_back(image);
    }
    return images;
  }

 private:
  Mesh model_;
  float radius_ = 0.0f;
  Rig rig_;
  std::vector<cv::Mat> backgrounds_;
  RenderBuffers buffers_;
};

// The reconfigurable cameras of one variant: where they are and where they go.
struct CameraSet {
  std::vector<StageState> states;
  std::vector<int> targets;  // feasible pose indices
  std::vector<bool> assigned;
  // Top-view position and yaw of the object, per frame, as the planner knows it.
  std::vector<Eigen::Vector3d> history;
};

// The object at the demand instants t_k + l * interval (l = 1..m), constant velocity over
// the last velocity_window_frames of `history` (the pose-prediction agent).
std::vector<BoundingEllipse> Predict(const ReconfigurationConfig& config,
                                     const std::vector<Eigen::Vector3d>& history) {
  const int k = static_cast<int>(history.size()) - 1;
  const int w = std::min(config.velocity_window_frames, k);
  Eigen::Vector3d rate = Eigen::Vector3d::Zero();
  if (w > 0) {
    rate = (history[k] - history[k - w]) * config.fps / w;
    rate.z() = WrapAngle(history[k].z() - history[k - w].z()) * config.fps / w;
  }
  const double interval_s = config.demand_interval_frames / config.fps;
  std::vector<BoundingEllipse> predicted;
  for (int l = 1; l <= config.planner.max_lookahead; ++l) {
    const Eigen::Vector3d p = history[k] + rate * l * interval_s;
    BoundingEllipse e;
    e.centre_m = p.head<2>();
    e.semi_axes_m = Eigen::Vector2d::Constant(config.object_edge_m / std::numbers::sqrt2);
    e.heading_rad = p.z();
    predicted.push_back(e);
  }
  return predicted;
}

Eigen::Vector3d TopViewPose(const Rigid3d& world_from_obj) {
  return {world_from_obj.translation().x(), world_from_obj.translation().z(), Yaw(world_from_obj)};
}

}  // namespace

ReconfigurationResult RunReconfiguration(const ReconfigurationConfig& config) {
  config.Check();
  const Timer total;
  std::vector<CameraAgent> agents;
  for (const StageCamera& c : config.cameras) agents.emplace_back(c);
  const int n = static_cast<int>(agents.size());
  const double interval_s = config.demand_interval_frames / config.fps;

  std::array<CameraSet, kNumVariants> sets;
  for (CameraSet& set : sets) {
    for (const CameraAgent& a : agents) {
      set.targets.push_back(a.NearestPose(a.camera().home));
      set.states.push_back(a.Pose(set.targets.back()));
    }
    set.assigned.assign(n, false);
  }

  std::optional<TrackingRig> rig;
  std::optional<Tracker> tracker;
  if (config.track) {
    rig.emplace(config);
    tracker.emplace(rig->rig(), rig->model());
    tracker->Initialize(TrueObjectPose(config, 0));
  }

  ReconfigurationResult result;
  double error_sum = 0.0;
  int lookahead_sum = 0;
  for (int k = 0; k < config.frames; ++k) {
    ReconfigurationFrame f;
    f.true_world_from_obj = TrueObjectPose(config, k);
    f.tracked_world_from_obj = f.true_world_from_obj;
    if (config.track) {
      Timer synth;
      const std::vector<cv::Mat> images = rig->Images(f.true_world_from_obj);
      result.synth_s += synth.ElapsedSeconds();
      Timer track;
      const TrackResult r = tracker->Track(images);
      result.track_s += track.ElapsedSeconds();
      f.tracked_world_from_obj = r.world_from_obj;
      f.status = r.status;
      if (r.status != TrackStatus::kTracking) ++result.lost_frames;
    }
    const double error =
        (f.tracked_world_from_obj.translation() - f.true_world_from_obj.translation()).norm();
    error_sum += error;
    result.max_position_error_m = std::max(result.max_position_error_m, error);
    sets[kTrackedPoses].history.push_back(TopViewPose(f.tracked_world_from_obj));
    sets[kTruePoses].history.push_back(TopViewPose(f.true_world_from_obj));

    // Demand instant: plan the next one (and look further ahead) for both reconfigured sets.
    if (k % config.demand_interval_frames == 0) {
      Timer plan;
      for (int v : {kTrackedPoses, kTruePoses}) {
        CameraSet& set = sets[v];
        const std::vector<BoundingEllipse> predicted = Predict(config, set.history);
        std::vector<int> current(n);
        for (int i = 0; i < n; ++i) current[i] = agents[i].NearestPose(set.states[i]);
        const CameraPlans plans = PlanCameras(agents, current, predicted, config.columns,
                                              interval_s, config.visibility, config.planner);
        for (int i = 0; i < n; ++i) {
          set.targets[i] = plans.cameras[i].pose_index;
          set.assigned[i] = plans.cameras[i].assigned;
        }
        lookahead_sum += plans.lookahead;
        ++result.plans;
      }
      result.plan_s += plan.ElapsedSeconds();
    }

    // Score what the cameras see of the true object now, then move them for one frame.
    const BoundingEllipse truth = ObjectEllipse(f.true_world_from_obj, config.object_edge_m);
    for (int v = 0; v < kNumVariants; ++v) {
      CameraSet& set = sets[v];
      f.states[v] = set.states;
      f.assigned[v] = set.assigned;
      for (int i = 0; i < n; ++i) {
        f.visibility[v].push_back(Visibility(agents[i].camera().ViewAt(set.states[i]), truth,
                                             config.columns, config.visibility));
        const StageCamera& c = agents[i].camera();
        const StageState target = agents[i].Pose(set.targets[i]);
        set.states[i].rail_m =
            StepTowards(set.states[i].rail_m, target.rail_m, c.rail_speed_m_s / config.fps);
        set.states[i].pan_rad =
            StepTowards(set.states[i].pan_rad, target.pan_rad, c.pan_speed_rad_s / config.fps);
      }
    }
    result.frames.push_back(std::move(f));
  }

  // Summary.
  const int frames = static_cast<int>(result.frames.size());
  for (int v = 0; v < kNumVariants; ++v) {
    result.camera_mean_visibility[v].assign(n, 0.0);
    double sum = 0.0;
    for (const ReconfigurationFrame& f : result.frames) {
      int seen = 0;
      for (int i = 0; i < n; ++i) {
        result.camera_mean_visibility[v][i] += f.visibility[v][i].value / frames;
        sum += f.visibility[v][i].value;
        if (f.visibility[v][i].area >= config.min_seen_share) ++seen;
      }
      if (seen < std::min(n, config.planner.assigned_cameras)) ++result.frames_seen_by_fewer[v];
    }
    result.mean_visibility[v] = sum / (frames * n);
  }
  for (const ReconfigurationFrame& f : result.frames) {
    double excess = 0.0;
    for (int i = 0; i < n; ++i) {
      excess += (f.visibility[kTrackedPoses][i].value - f.visibility[kTruePoses][i].value) / n;
    }
    if (excess <= 0.02) ++result.frames_tracked_not_above;
    result.max_tracked_excess = std::max(result.max_tracked_excess, excess);
  }
  result.mean_position_error_m = error_sum / frames;
  result.mean_lookahead = result.plans > 0 ? double(lookahead_sum) / result.plans : 0.0;
  result.total_s = total.ElapsedSeconds();
  return result;
}

}  // namespace unseen
