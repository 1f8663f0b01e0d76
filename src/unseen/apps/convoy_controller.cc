// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/apps/convoy_controller.h"

#include <algorithm>
#include <cmath>

#include "unseen/util/error.h"

namespace unseen {

Eigen::Vector2d PlanarPose::Direction() const {
  return Eigen::Vector2d(std::cos(heading_rad), std::sin(heading_rad));
}

double WrapAngle(double angle_rad) {
  double a = std::remainder(angle_rad, 2.0 * M_PI);
  if (a <= -M_PI) a += 2.0 * M_PI;
  return a;
}

VehicleState IntegrateUnicycle(const VehicleState& state, double acceleration_m_s2,
                               double angular_velocity_rad_s, double dt_s, double max_speed_m_s) {
  VehicleState next;
  next.speed_m_s = std::clamp(state.speed_m_s + acceleration_m_s2 * dt_s, 0.0, max_speed_m_s);
  next.angular_velocity_rad_s = angular_velocity_rad_s;
  const double turn = angular_velocity_rad_s * dt_s;
  const double distance = next.speed_m_s * dt_s;
  const double theta = state.pose.heading_rad;
  Eigen::Vector2d step;
  if (std::abs(turn) < 1e-9) {
    step = distance * state.pose.Direction();
  } else {  // the exact arc of radius distance / turn
    const double r = distance / turn;
    step = Eigen::Vector2d(r * (std::sin(theta + turn) - std::sin(theta)),
                           r * (std::cos(theta) - std::cos(theta + turn)));
  }
  next.pose.position = state.pose.position + step;
  next.pose.heading_rad = WrapAngle(theta + turn);
  return next;
}

void ConvoyControllerOptions::Check() const {
  UNSEEN_CHECK(separation_m > 0, "convoy controller: separation_m {} must be > 0", separation_m);
  UNSEEN_CHECK(separation_gain > 0, "convoy controller: separation_gain {} must be > 0",
               separation_gain);
  UNSEEN_CHECK(speed_gain >= 0, "convoy controller: speed_gain {} must be >= 0", speed_gain);
  UNSEEN_CHECK(look_ahead_m > 0, "convoy controller: look_ahead_m {} must be > 0", look_ahead_m);
  UNSEEN_CHECK(pursuit_gain > 0, "convoy controller: pursuit_gain {} must be > 0", pursuit_gain);
  UNSEEN_CHECK(heading_gain >= 0, "convoy controller: heading_gain {} must be >= 0", heading_gain);
  UNSEEN_CHECK(min_spacing_m >= 0 && min_spacing_m < look_ahead_m,
               "convoy controller: min_spacing_m {} must be in [0, look_ahead_m)", min_spacing_m);
  UNSEEN_CHECK(lead_speed_frames >= 1, "convoy controller: lead_speed_frames {} must be >= 1",
               lead_speed_frames);
  UNSEEN_CHECK(max_acceleration_m_s2 > 0, "convoy controller: max_acceleration_m_s2 {} must be > 0",
               max_acceleration_m_s2);
  UNSEEN_CHECK(max_angular_velocity_rad_s > 0,
               "convoy controller: max_angular_velocity_rad_s {} must be > 0",
               max_angular_velocity_rad_s);
  UNSEEN_CHECK(max_speed_m_s > 0, "convoy controller: max_speed_m_s {} must be > 0", max_speed_m_s);
  UNSEEN_CHECK(frame_interval_s > 0, "convoy controller: frame_interval_s {} must be > 0",
               frame_interval_s);
  // A conservative bound for the discrete speed loop (one Euler step of
  // e'' = -c1 e - c2 e' per frame), which oscillates and diverges as c2 dt + c1 dt² nears 4.
  const double dt = frame_interval_s;
  UNSEEN_CHECK(speed_gain * dt + separation_gain * dt * dt < 2.0,
               "convoy controller: separation_gain {} and speed_gain {} are too high for "
               "frame_interval_s {} (need c2 dt + c1 dt² < 2)",
               separation_gain, speed_gain, frame_interval_s);
}

ConvoyController::ConvoyController(const ConvoyControllerOptions& options) : options_(options) {
  options_.Check();
}

void ConvoyController::Reset(const PlanarPose& lead) {
  stored_.assign(1, lead);
  latest_ = lead;
  recent_positions_.assign(1, lead.position);
}

std::vector<PlanarPose> ConvoyController::Path() const {
  std::vector<PlanarPose> path(stored_.begin(), stored_.end());
  if (latest_ && (path.empty() || (latest_->position - path.back().position).norm() > 0)) {
    path.push_back(*latest_);
  }
  return path;
}

ConvoyCommand ConvoyController::Step(const VehicleState& follower,
                                     const std::optional<PlanarPose>& lead) {
  UNSEEN_CHECK(latest_.has_value(), "ConvoyController::Step before Reset");
  const ConvoyControllerOptions& o = options_;
  ConvoyCommand c;
  c.measured = lead.has_value();
  // (4.28): the new measurement joins A_i once it is min_spacing_m from the last one.
  if (lead) {
    latest_ = *lead;
    if ((lead->position - stored_.back().position).norm() >= o.min_spacing_m) {
      stored_.push_back(*lead);
    }
  }
  recent_positions_.push_back(latest_->position);
  while (static_cast<int>(recent_positions_.size()) > o.lead_speed_frames + 1) {
    recent_positions_.pop_front();
  }
  // Drop the poses the follower has passed (4.5.2), keeping the newest.
  const Eigen::Vector2d p_f = follower.pose.position;
  const Eigen::Vector2d dir_f = follower.pose.Direction();
  while (stored_.size() > 1 && (stored_.front().position - p_f).dot(dir_f) <= 0.0) {
    stored_.pop_front();
  }
  const std::vector<PlanarPose> path = Path();

  // (4.29): d = |p_1 - p_f| + Σ |p_{n+1} - p_n|; on the way, the look-ahead point p_j of
  // (4.30) at arc length L (the lead's pose when the path is shorter).
  Eigen::Vector2d look_ahead = path.back().position;
  bool look_ahead_found = false;
  Eigen::Vector2d prev = p_f;
  double d = 0.0;
  for (const PlanarPose& p : path) {
    const double segment = (p.position - prev).norm();
    if (!look_ahead_found && d + segment >= o.look_ahead_m && segment > 0) {
      look_ahead = prev + (o.look_ahead_m - d) / segment * (p.position - prev);
      look_ahead_found = true;
    }
    d += segment;
    prev = p.position;
  }
  c.following_distance_m = d;
  const Eigen::Vector2d to_point = look_ahead - p_f;
  if (to_point.norm() > 1e-9) {
    c.look_ahead_angle_rad =
        WrapAngle(std::atan2(to_point.y(), to_point.x()) - follower.pose.heading_rad);
  }
  // (4.31): ψ = θ_d - θ with θ_d the orientation of P_1.
  c.heading_error_rad = WrapAngle(path.front().heading_rad - follower.pose.heading_rad);

  const int n = static_cast<int>(recent_positions_.size()) - 1;
  if (n > 0) {
    c.lead_speed_m_s =
        (recent_positions_.back() - recent_positions_.front()).norm() / (n * o.frame_interval_s);
  }
  // (4.27).
  const double a = o.separation_gain * (d - o.separation_m) +
                   o.speed_gain * (c.lead_speed_m_s - follower.speed_m_s);
  c.acceleration_m_s2 = std::clamp(a, -o.max_acceleration_m_s2, o.max_acceleration_m_s2);
  const double curvature = (o.pursuit_gain * 2.0 * std::sin(c.look_ahead_angle_rad) +
                            o.heading_gain * c.heading_error_rad) /
                           o.look_ahead_m;
  c.angular_velocity_rad_s = std::clamp(
      follower.speed_m_s * curvature, -o.max_angular_velocity_rad_s, o.max_angular_velocity_rad_s);
  c.stored_poses = static_cast<int>(stored_.size());
  return c;
}

}  // namespace unseen
