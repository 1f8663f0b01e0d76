// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/apps/convoy.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "unseen/mesh/primitives.h"
#include "unseen/synth/clutter.h"
#include "unseen/util/error.h"
#include "unseen/util/timer.h"
#include "unseen/util/yaml_options.h"

namespace unseen {

namespace {

constexpr double kDeg = M_PI / 180.0;

std::vector<LeadPhase> ParseLeadPhases(const YAML::Node& node, const std::string& where) {
  UNSEEN_CHECK(node.IsSequence(), "{}: expected a list of phases", where);
  std::vector<LeadPhase> phases;
  for (std::size_t i = 0; i < node.size(); ++i) {
    LeadPhase p;
    ApplyYamlSection(node[i], fmt::format("{}[{}]", where, i),
                     {{"duration_s", YamlField(&p.duration_s)},
                      {"end_speed_mm_s", YamlScaledField(&p.end_speed_m_s, 1e-3)},
                      {"yaw_rate_deg_s", YamlScaledField(&p.yaw_rate_rad_s, kDeg)}});
    phases.push_back(p);
  }
  return phases;
}

// The ground: a grid of 1 m squares over `min`..`max` (planar) at Y = `height_m`, its
// texture (a softened clutter image) repeating every `tile_m`.
Mesh MakeGround(const Eigen::Vector2d& min, const Eigen::Vector2d& max, double height_m,
                double tile_m, uint64_t seed) {
  Mesh ground;
  Material m;
  m.name = "ground";
  // The clutter image at half its contrast: asphalt, not a poster wall.
  MakeClutterImage(256, 256, seed).convertTo(m.texture, CV_32FC3, 0.5, 0.25);
  ground.materials.push_back(m);
  const int nx = std::max(1, static_cast<int>(std::ceil(max.x() - min.x())));
  const int ny = std::max(1, static_cast<int>(std::ceil(max.y() - min.y())));
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      const double x = min.x() + i, y = min.y() + j;
      ground.vertices.emplace_back(x, height_m, y);
      ground.uvs.emplace_back(x / tile_m, y / tile_m);
    }
  }
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
      ground.triangles.emplace_back(a, c, b);
      ground.triangles.emplace_back(b, c, d);
    }
  }
  ground.Check("convoy ground");
  return ground;
}

double Rms(double sum_sq, int n) { return n > 0 ? std::sqrt(sum_sq / n) : 0.0; }

}  // namespace

std::vector<LeadPhase> ThesisLeadDrive() {
  const double v = 0.720, turn = 20.0 * kDeg;
  return {{2.0, v, 0.0},   {1.0, v, 0.0}, {4.5, v, turn},
          {4.5, v, -turn}, {1.0, v, 0.0}, {2.0, 0.0, 0.0}};
}

void ConvoyOptions::Check() const {
  UNSEEN_CHECK(vehicle_size_m > 0, "convoy: vehicle_size_m {} must be > 0", vehicle_size_m);
  UNSEEN_CHECK(image_width_px >= 16 && image_height_px >= 16,
               "convoy: image size {}x{} must be at least 16x16", image_width_px, image_height_px);
  UNSEEN_CHECK(focal_px > 0, "convoy: focal_px {} must be > 0", focal_px);
  UNSEEN_CHECK(frame_interval_s > 0, "convoy: frame_interval_s {} must be > 0", frame_interval_s);
  UNSEEN_CHECK(!lead_drive.empty(), "convoy: the lead's drive has no phases");
  for (const LeadPhase& p : lead_drive) {
    UNSEEN_CHECK(p.duration_s > 0 && p.end_speed_m_s >= 0 && std::isfinite(p.yaw_rate_rad_s),
                 "convoy: a lead phase needs duration_s > 0 (got {}) and end speed >= 0 (got "
                 "{} m/s)",
                 p.duration_s, p.end_speed_m_s);
  }
  UNSEEN_CHECK(settle_s >= 0, "convoy: settle_s {} must be >= 0", settle_s);
  UNSEEN_CHECK(jitter_px_3sigma >= 0, "convoy: jitter_px_3sigma {} must be >= 0", jitter_px_3sigma);
  UNSEEN_CHECK(supersample >= 1 && supersample <= 4, "convoy: supersample {} must be in [1, 4]",
               supersample);
  UNSEEN_CHECK(ground_tile_m > 0, "convoy: ground_tile_m {} must be > 0", ground_tile_m);
  UNSEEN_CHECK(controller.separation_m > vehicle_size_m,
               "convoy: the separation {} m must exceed the vehicle size {} m",
               controller.separation_m, vehicle_size_m);
  UNSEEN_CHECK(std::abs(controller.frame_interval_s - frame_interval_s) < 1e-9,
               "convoy: the controller's frame interval {} s differs from the frame interval {} s",
               controller.frame_interval_s, frame_interval_s);
  controller.Check();
  tracker.Check();
}

namespace {

// The options `root` (a parsed configuration) sets over the defaults; `what` names it.
ConvoyOptions ConvoyOptionsFromYaml(const YAML::Node& root, const std::string& what) {
  ConvoyOptions o;
  if (root.IsNull()) return o;
  UNSEEN_CHECK(root.IsMap(), "{}: expected a map of sections", what);
  double fps = 1.0 / o.frame_interval_s;
  ConvoyControllerOptions& c = o.controller;
  const std::map<std::string, YamlSection> sections = {
      {"run",
       {{"fps", YamlField(&fps)},
        {"settle_s", YamlField(&o.settle_s)},
        {"seed", YamlField(&o.seed)},
        {"use_tracker", YamlField(&o.use_tracker)}}},
      {"vehicles", {{"size_mm", YamlScaledField(&o.vehicle_size_m, 1e-3)}}},
      {"camera",
       {{"width_px", YamlField(&o.image_width_px)},
        {"height_px", YamlField(&o.image_height_px)},
        {"focal_px", YamlField(&o.focal_px)}}},
      {"render",
       {{"jitter_px_3sigma", YamlField(&o.jitter_px_3sigma)},
        {"supersample", YamlField(&o.supersample)},
        {"ground", YamlField(&o.ground)},
        {"ground_tile_mm", YamlScaledField(&o.ground_tile_m, 1e-3)}}},
      {"controller",
       {{"separation_mm", YamlScaledField(&c.separation_m, 1e-3)},
        {"separation_gain", YamlField(&c.separation_gain)},
        {"speed_gain", YamlField(&c.speed_gain)},
        {"look_ahead_mm", YamlScaledField(&c.look_ahead_m, 1e-3)},
        {"pursuit_gain", YamlField(&c.pursuit_gain)},
        {"heading_gain", YamlField(&c.heading_gain)},
        {"min_spacing_mm", YamlScaledField(&c.min_spacing_m, 1e-3)},
        {"lead_speed_frames", YamlField(&c.lead_speed_frames)},
        {"max_acceleration_mm_s2", YamlScaledField(&c.max_acceleration_m_s2, 1e-3)},
        {"max_angular_velocity_deg_s", YamlScaledField(&c.max_angular_velocity_rad_s, kDeg)},
        {"max_speed_mm_s", YamlScaledField(&c.max_speed_m_s, 1e-3)}}}};
  for (const auto& kv : root) {
    const std::string key = YamlKeyName(kv.first, what);
    const std::string where = what + ": " + key;
    if (key == "lead") {
      UNSEEN_CHECK(kv.second.IsMap() && kv.second["phases"], "{}: expected 'phases: [...]'", where);
      o.lead_drive = ParseLeadPhases(kv.second["phases"], where + ".phases");
    } else if (key == "tracker") {
      o.tracker = ParseTrackerOptions(YAML::Dump(kv.second), where);
    } else if (const auto it = sections.find(key); it != sections.end()) {
      ApplyYamlSection(kv.second, where, it->second);
    } else {
      ThrowError(
          "{}: unknown section '{}' (known: run, vehicles, camera, render, lead, controller, "
          "tracker)",
          what, key);
    }
  }
  UNSEEN_CHECK(fps > 0, "{}: run.fps {} must be > 0", what, fps);
  o.frame_interval_s = 1.0 / fps;
  o.controller.frame_interval_s = o.frame_interval_s;
  o.tracker.frame_interval_s = o.frame_interval_s;
  CheckOptionsFrom(o, what);
  return o;
}

}  // namespace

ConvoyOptions ParseConvoyOptions(const std::string& yaml_text, const std::string& what) {
  const YAML::Node root = ParseYamlText(yaml_text, what);
  return ConvoyOptionsFromYaml(root, what);
}

ConvoyOptions LoadConvoyOptions(const std::string& path) {
  return ConvoyOptionsFromYaml(LoadYamlFile(path, "convoy configuration"), path);
}

PlanarPose PlanarFromWorld(const Rigid3d& world_from_vehicle) {
  const Eigen::Vector3d forward = world_from_vehicle.rotation() * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d& t = world_from_vehicle.translation();
  PlanarPose p;
  p.position = Eigen::Vector2d(t.x(), t.z());
  p.heading_rad = std::atan2(forward.z(), forward.x());
  return p;
}

Rigid3d WorldFromPlanar(const PlanarPose& pose) {
  const double c = std::cos(pose.heading_rad), s = std::sin(pose.heading_rad);
  Eigen::Matrix3d r;
  r.col(0) << s, 0, -c;  // right
  r.col(1) << 0, 1, 0;   // down
  r.col(2) << c, 0, s;   // forward
  return Rigid3d(Eigen::Quaterniond(r), Eigen::Vector3d(pose.position.x(), 0.0, pose.position.y()));
}

ConvoySimulation::ConvoySimulation(const ConvoyOptions& options)
    : options_(options), controller_(options.controller), rng_(options.seed) {
  options_.Check();
  camera_ =
      PinholeCamera::Centered(options_.image_width_px, options_.image_height_px, options_.focal_px);
  lead_model_ = MakeTexturedBox(Eigen::Vector3d::Constant(options_.vehicle_size_m));

  // The lead's drive, integrated in 10 sub-steps a frame; it starts at rest, D ahead.
  const double dt = options_.frame_interval_s;
  double total_s = options_.settle_s;
  for (const LeadPhase& p : options_.lead_drive) total_s += p.duration_s;
  const int frames = static_cast<int>(std::floor(total_s / dt + 1e-9)) + 1;
  VehicleState lead;
  lead.pose.position = Eigen::Vector2d(0.0, options_.controller.separation_m);
  lead.pose.heading_rad = M_PI / 2;
  follower_.pose.heading_rad = M_PI / 2;
  constexpr int kSubSteps = 10;
  for (int k = 0; k < frames; ++k) {
    lead_states_.push_back(lead);
    for (int s = 0; s < kSubSteps; ++s) {
      const double t = (k + (s + 0.5) / kSubSteps) * dt;
      double phase_start = 0.0, start_speed = 0.0;
      LeadPhase phase{1.0, 0.0, 0.0};  // after the drive: at rest
      for (const LeadPhase& p : options_.lead_drive) {
        if (t < phase_start + p.duration_s) {
          phase = p;
          break;
        }
        phase_start += p.duration_s;
        start_speed = p.end_speed_m_s;
      }
      const double accel = (phase.end_speed_m_s - start_speed) / phase.duration_s;
      lead = IntegrateUnicycle(lead, accel, phase.yaw_rate_rad_s, dt / kSubSteps, 1e3);
    }
  }
  lead_path_.push_back(follower_.pose);
  for (const VehicleState& s : lead_states_) lead_path_.push_back(s.pose);
  lead_path_arc_m_.push_back(0.0);
  for (std::size_t i = 1; i < lead_path_.size(); ++i) {
    lead_path_arc_m_.push_back(lead_path_arc_m_.back() +
                               (lead_path_[i].position - lead_path_[i - 1].position).norm());
  }

  const int s = options_.supersample;
  const PinholeCamera fine = camera_.Scaled(1.0 / s);
  // The sky: light blue at the top fading to haze at the horizon.
  sky_.create(fine.height, fine.width, CV_32FC3);
  for (int y = 0; y < fine.height; ++y) {
    const float u = static_cast<float>(y) / fine.height;
    sky_.row(y).setTo(cv::Scalar(0.95 - 0.15 * u, 0.80 - 0.05 * u, 0.60 + 0.2 * u));
  }
  if (options_.ground) {
    Eigen::Vector2d min = lead_path_[0].position, max = min;
    for (const PlanarPose& p : lead_path_) {
      min = min.cwiseMin(p.position);
      max = max.cwiseMax(p.position);
    }
    const Eigen::Vector2d margin(3.0, 3.0);
    ground_ = MakeGround(min - margin, max + margin, options_.vehicle_size_m / 2,
                         options_.ground_tile_m, options_.seed);
  }

  const Rigid3d cam_from_lead =
      WorldFromPlanar(follower_.pose).Inverse() * WorldFromPlanar(lead_states_[0].pose);
  if (options_.use_tracker) {
    Rig rig;
    rig.cameras.push_back({"follower", camera_, Rigid3d()});
    tracker_ = std::make_unique<Tracker>(rig, lead_model_, options_.tracker);
    // The tracker starts at the true first relative pose (its world is the camera frame).
    tracker_->Initialize(cam_from_lead);
  }
  controller_.Reset(lead_states_[0].pose);
  last_tracked_ = lead_states_[0].pose;
}

ConvoySimulation::~ConvoySimulation() = default;

cv::Mat ConvoySimulation::RenderView(const Rigid3d& world_from_cam, const Rigid3d& cam_from_lead) {
  const int s = options_.supersample;
  const PinholeCamera fine = camera_.Scaled(1.0 / s);
  cv::Mat image = sky_.clone();
  if (options_.ground) {
    RenderOptions ground_options;
    ground_options.cull_back_faces = false;
    // The ground lies below the horizon (the camera is level, above it).
    PixelRect below = fine.ImageRect();
    below.y0 = std::max(0, static_cast<int>(std::floor(fine.cy)) - 1);
    Render(ground_, fine, world_from_cam.Inverse(), below, ground_options, &buffers_);
    buffers_.color.copyTo(image(ToCvRect(below)), buffers_.mask);
  }
  Render(lead_model_, fine, cam_from_lead, fine.ImageRect(), RenderOptions(), &buffers_);
  buffers_.color.copyTo(image, buffers_.mask);
  if (s == 1) return image;
  cv::Mat out;
  cv::resize(image, out, cv::Size(camera_.width, camera_.height), 0, 0, cv::INTER_AREA);
  return out;
}

void ConvoySimulation::PathErrors(const Eigen::Vector2d& follower, int frame,
                                  double* separation_error_m, double* cross_track_m) {
  // Segment i joins lead_path_[i] and [i + 1]; the lead is at lead_path_[frame + 1].
  const int last = frame;  // the last segment ending at the lead
  double best = std::numeric_limits<double>::infinity(), best_arc = 0.0;
  int best_i = path_hint_;
  for (int i = std::max(0, path_hint_ - 5); i <= std::min(last, path_hint_ + 300); ++i) {
    const Eigen::Vector2d a = lead_path_[i].position, b = lead_path_[i + 1].position;
    const double len2 = (b - a).squaredNorm();
    const double u = len2 > 0 ? std::clamp((follower - a).dot(b - a) / len2, 0.0, 1.0) : 0.0;
    const double dist = (a + u * (b - a) - follower).norm();
    if (dist < best) {
      best = dist;
      best_i = i;
      best_arc = lead_path_arc_m_[i] + u * std::sqrt(len2);
    }
  }
  path_hint_ = best_i;
  *cross_track_m = best;
  *separation_error_m = lead_path_arc_m_[frame + 1] - best_arc - options_.controller.separation_m;
}

ConvoyFrame ConvoySimulation::Step() {
  UNSEEN_CHECK(!Done(), "ConvoySimulation::Step: all {} frames simulated", NumFrames());
  ConvoyFrame f;
  f.frame = frame_;
  f.time_s = frame_ * options_.frame_interval_s;
  f.lead_true = lead_states_[frame_].pose;
  f.follower = follower_;
  const Rigid3d world_from_cam = WorldFromPlanar(follower_.pose);
  Rigid3d cam_from_lead = world_from_cam.Inverse() * WorldFromPlanar(f.lead_true);
  // The jitter [4.5.3]: 3σ = jitter_px_3sigma on screen, at the lead's depth.
  const double sigma_m =
      options_.jitter_px_3sigma / 3.0 * cam_from_lead.translation().z() / options_.focal_px;
  Eigen::Vector3d t = cam_from_lead.translation();
  t.x() += rng_.gaussian(sigma_m);
  t.y() += rng_.gaussian(sigma_m);
  cam_from_lead.set_translation(t);
  const Rigid3d world_from_rendered = world_from_cam * cam_from_lead;
  f.lead_rendered = PlanarFromWorld(world_from_rendered);

  Rigid3d world_from_tracked = world_from_rendered;
  if (tracker_) {
    Timer timer;
    Frame frame;
    frame.frame_id = frame_;
    frame.time_s = f.time_s;
    last_image_ = RenderView(world_from_cam, cam_from_lead);
    frame.images.push_back(last_image_);
    f.render_ms = timer.ElapsedMilliseconds();
    timer.Restart();
    const TrackResult r = tracker_->Track(frame);
    f.track_ms = timer.ElapsedMilliseconds();
    f.tracked = r.status == TrackStatus::kTracking;
    f.confidence = r.confidence;
    world_from_tracked = world_from_cam * r.world_from_obj;
  } else {
    f.tracked = true;
    f.confidence = 1.0;
  }
  std::optional<PlanarPose> measured;
  if (f.tracked) {
    last_tracked_ = PlanarFromWorld(world_from_tracked);
    measured = last_tracked_;
    f.tracking_error_m = last_tracked_.position - f.lead_rendered.position;
    f.tracking_error_heading_rad =
        WrapAngle(last_tracked_.heading_rad - f.lead_rendered.heading_rad);
    f.error_to_true_m = last_tracked_.position - f.lead_true.position;
    f.tracking_error_3d_m =
        (world_from_tracked.translation() - world_from_rendered.translation()).norm();
  }
  f.lead_tracked = last_tracked_;
  PathErrors(follower_.pose.position, frame_, &f.separation_error_m, &f.cross_track_m);
  f.command = controller_.Step(follower_, measured);
  follower_ =
      IntegrateUnicycle(follower_, f.command.acceleration_m_s2, f.command.angular_velocity_rad_s,
                        options_.frame_interval_s, options_.controller.max_speed_m_s);
  ++frame_;
  return f;
}

ConvoyResult ConvoySimulation::Run(int max_frames,
                                   const std::function<void(const ConvoyFrame&)>& on_frame) {
  ConvoyResult result;
  result.lead_path = lead_path_;
  const int n = max_frames > 0 ? std::min(max_frames, NumFrames() - frame_) : NumFrames() - frame_;
  Timer timer;
  double callback_s = 0.0;  // not part of the simulation's speed
  for (int k = 0; k < n; ++k) {
    result.frames.push_back(Step());
    if (on_frame) {
      Timer callback;
      on_frame(result.frames.back());
      callback_s += callback.ElapsedSeconds();
    }
  }
  ConvoySummary& s = result.summary;
  s.seconds = timer.ElapsedSeconds() - callback_s;
  s.frames = n;
  s.frames_per_second = s.seconds > 0 ? n / s.seconds : 0.0;
  double sx = 0, sy = 0, sh = 0, tx = 0, ty = 0, render = 0, track = 0;
  for (const ConvoyFrame& f : result.frames) {
    render += f.render_ms;
    track += f.track_ms;
    s.min_separation_error_m = std::min(s.min_separation_error_m, f.separation_error_m);
    s.max_separation_error_m = std::max(s.max_separation_error_m, f.separation_error_m);
    s.max_cross_track_m = std::max(s.max_cross_track_m, f.cross_track_m);
    if (!f.tracked) {
      ++s.lost;
      continue;
    }
    ++s.tracked;
    sx += f.tracking_error_m.x() * f.tracking_error_m.x();
    sy += f.tracking_error_m.y() * f.tracking_error_m.y();
    sh += f.tracking_error_heading_rad * f.tracking_error_heading_rad;
    tx += f.error_to_true_m.x() * f.error_to_true_m.x();
    ty += f.error_to_true_m.y() * f.error_to_true_m.y();
    s.max_tracking_3d_m = std::max(s.max_tracking_3d_m, f.tracking_error_3d_m);
  }
  s.rms_tracking_x_m = Rms(sx, s.tracked);
  s.rms_tracking_y_m = Rms(sy, s.tracked);
  s.rms_tracking_heading_rad = Rms(sh, s.tracked);
  s.rms_true_x_m = Rms(tx, s.tracked);
  s.rms_true_y_m = Rms(ty, s.tracked);
  s.mean_render_ms = n > 0 ? render / n : 0.0;
  s.mean_track_ms = n > 0 ? track / n : 0.0;
  return result;
}

std::string ConvoySummary::Report() const {
  std::string out;
  out += fmt::format("{:<34} {:>16} {:>16}\n", "convoy (1 unit = 1 mm)", "unseen", "thesis");
  out += fmt::format("{:<34} {:>7.2f} / {:<6.2f} {:>16}\n", "RMS tracking error x / y (units)",
                     1e3 * rms_tracking_x_m, 1e3 * rms_tracking_y_m, "0.31 / 0.35");
  out += fmt::format("{:<34} {:>7.2f} / {:<6.2f} {:>16}\n", "  x / y against the unjittered pose",
                     1e3 * rms_true_x_m, 1e3 * rms_true_y_m, "-");
  out += fmt::format("{:<34} {:>16.2f} {:>16}\n", "RMS heading error (deg)",
                     rms_tracking_heading_rad / kDeg, "0.51");
  out += fmt::format("{:<34} {:>16.2f} {:>16}\n", "max 3-D tracking error (units)",
                     1e3 * max_tracking_3d_m, "-");
  out += fmt::format("{:<34} {:>+7.2f} .. {:<+6.2f} {:>16}\n", "separation error (units)",
                     1e3 * min_separation_error_m, 1e3 * max_separation_error_m, "within ±5");
  out += fmt::format("{:<34} {:>16.2f} {:>16}\n", "max cross-track error (units)",
                     1e3 * max_cross_track_m, "< 3");
  out += fmt::format("{:<34} {:>7d} / {:<6d} {:>16}\n", "frames tracked / lost", tracked, lost,
                     "all tracked");
  out += fmt::format("{:<34} {:>16.1f} {:>16}\n", "simulated frames per second", frames_per_second,
                     "33-35 (GPU)");
  out += fmt::format("{:<34} {:>7.1f} / {:<6.1f} {:>16}\n", "mean render / track ms",
                     mean_render_ms, mean_track_ms, "-");
  return out;
}

nlohmann::json ConvoySummary::ToJson() const {
  return {{"frames", frames},
          {"tracked", tracked},
          {"lost", lost},
          {"rms_tracking_x_mm", 1e3 * rms_tracking_x_m},
          {"rms_tracking_y_mm", 1e3 * rms_tracking_y_m},
          {"rms_tracking_heading_deg", rms_tracking_heading_rad / kDeg},
          {"max_tracking_3d_mm", 1e3 * max_tracking_3d_m},
          {"rms_true_x_mm", 1e3 * rms_true_x_m},
          {"rms_true_y_mm", 1e3 * rms_true_y_m},
          {"min_separation_error_mm", 1e3 * min_separation_error_m},
          {"max_separation_error_mm", 1e3 * max_separation_error_m},
          {"max_cross_track_mm", 1e3 * max_cross_track_m},
          {"seconds", seconds},
          {"frames_per_second", frames_per_second},
          {"mean_render_ms", mean_render_ms},
          {"mean_track_ms", mean_track_ms}};
}

nlohmann::json ConvoyResult::ToJson() const {
  nlohmann::json frames_json = nlohmann::json::array();
  const auto pose = [](const PlanarPose& p) {
    return nlohmann::json::array({p.position.x(), p.position.y(), p.heading_rad});
  };
  for (const ConvoyFrame& f : frames) {
    frames_json.push_back({{"frame", f.frame},
                           {"time_s", f.time_s},
                           {"lead_true", pose(f.lead_true)},
                           {"lead_rendered", pose(f.lead_rendered)},
                           {"lead_tracked", pose(f.lead_tracked)},
                           {"tracked", f.tracked},
                           {"confidence", f.confidence},
                           {"follower", pose(f.follower.pose)},
                           {"follower_speed_m_s", f.follower.speed_m_s},
                           {"acceleration_m_s2", f.command.acceleration_m_s2},
                           {"angular_velocity_rad_s", f.command.angular_velocity_rad_s},
                           {"following_distance_m", f.command.following_distance_m},
                           {"look_ahead_angle_rad", f.command.look_ahead_angle_rad},
                           {"heading_error_rad", f.command.heading_error_rad},
                           {"lead_speed_m_s", f.command.lead_speed_m_s},
                           {"tracking_error_m", {f.tracking_error_m.x(), f.tracking_error_m.y()}},
                           {"tracking_error_heading_rad", f.tracking_error_heading_rad},
                           {"separation_error_m", f.separation_error_m},
                           {"cross_track_m", f.cross_track_m}});
  }
  return {{"units", "m, rad (planar x, y: top view; 1 thesis unit = 1 mm)"},
          {"summary", summary.ToJson()},
          {"frames", frames_json}};
}

}  // namespace unseen
