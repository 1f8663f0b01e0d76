// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The convoy controller of the thesis (SPEC 7.1, [4.5.1-4.5.2], (4.27)-(4.31)): the
// following vehicle keeps the lead's tracked poses A_i (4.28), measures the following
// distance d_i along them (4.29), the look-ahead angle φ_i (4.30) and the heading error
// ψ_i (4.31), and commands a linear acceleration and an angular velocity (4.27).
//
// Everything here is planar, in the top view of the ground: (x, y) metres with x right and
// y forward at the start, heading θ in radians from +x, counter-clockwise (a left turn
// increases θ). No images: the lead's poses come from whatever measures them.
#pragma once

#include <Eigen/Core>
#include <deque>
#include <optional>
#include <vector>

namespace unseen {

// A vehicle's planar pose: position (metres) and heading (radians, CCW from +x).
struct PlanarPose {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  double heading_rad = 0.0;
  // The unit direction of travel (cos θ, sin θ).
  Eigen::Vector2d Direction() const;
};

// `angle_rad` wrapped to (-π, π].
double WrapAngle(double angle_rad);

// A unicycle: planar pose, speed along the heading and angular velocity.
struct VehicleState {
  PlanarPose pose;
  double speed_m_s = 0.0;
  double angular_velocity_rad_s = 0.0;
};

// Integrates `state` over `dt_s` under the commands (acceleration first, then the speed
// clamped to [0, max_speed_m_s], no reversing), moving along the exact arc of the new speed
// and angular velocity. Returns the new state.
VehicleState IntegrateUnicycle(const VehicleState& state, double acceleration_m_s2,
                               double angular_velocity_rad_s, double dt_s, double max_speed_m_s);

struct ConvoyControllerOptions {
  double separation_m = 0.300;  // D: the set following distance along the lead's path
  // (4.27) linear row: a = c1 (d - D) + c2 (v_lead - v).
  double separation_gain = 200.0;  // c1, 1/s²
  double speed_gain = 20.0;        // c2, 1/s
  // (4.27) angular row, scheduled on the speed v so the follower does not turn on the
  // spot: ω = v (c3 · 2 sin φ + c4 ψ) / L. With c3 = 1 the φ term is pure pursuit, which
  // drives exactly along a circular path; the ψ term adds the lead's tracked orientation.
  // (The thesis's garbled (4.27) reads c3 (φ - ω) + c4 (ψ - ω); with ω' a velocity command
  // the ω terms only rescale the gains, and are left out.)
  double look_ahead_m = 0.100;  // L: distance along A_i of the point p_j of (4.30)
  double pursuit_gain = 1.0;    // c3, dimensionless
  double heading_gain = 0.5;    // c4, dimensionless
  // A_i (4.28) takes a measured lead pose only this far from the last stored one (tracker
  // noise would otherwise lengthen d while the lead stands).
  double min_spacing_m = 0.004;
  // The lead's speed v_lead is the chord of its last measurements over this many frames.
  int lead_speed_frames = 2;
  double max_acceleration_m_s2 = 3.0;       // |a| limit of the drive
  double max_angular_velocity_rad_s = 3.0;  // |ω| limit of the drive
  double max_speed_m_s = 2.0;
  double frame_interval_s = 1.0 / 30.0;  // one controller step, s
  void Check() const;
};

// The controller's inputs and outputs of one step.
struct ConvoyCommand {
  double acceleration_m_s2 = 0.0;       // a_i
  double angular_velocity_rad_s = 0.0;  // ω'_i
  double following_distance_m = 0.0;    // d_i (4.29)
  double look_ahead_angle_rad = 0.0;    // φ_i (4.30)
  double heading_error_rad = 0.0;       // ψ_i (4.31)
  double lead_speed_m_s = 0.0;          // v_{i-1} from the measurements
  int stored_poses = 0;                 // |A_i| after the step
  bool measured = false;                // the step had a lead measurement
};

class ConvoyController {
 public:
  explicit ConvoyController(const ConvoyControllerOptions& options = {});

  // Starts over: A_i holds only `lead` (measured), the follower is at `follower`.
  void Reset(const PlanarPose& lead);

  // One step (4.5.2): adds the lead's measured pose to A_i (none while the tracker has lost
  // it: the stored path is followed), computes d, φ, ψ and the commands, then drops the
  // stored poses the follower has passed. Throws before Reset().
  ConvoyCommand Step(const VehicleState& follower, const std::optional<PlanarPose>& lead);

  // A_i, nearest the follower first, then the last measured lead pose if it was not stored.
  std::vector<PlanarPose> Path() const;
  const ConvoyControllerOptions& options() const { return options_; }

 private:
  ConvoyControllerOptions options_;
  std::deque<PlanarPose> stored_;                 // A_i (4.28), nearest the follower first
  std::optional<PlanarPose> latest_;              // the last measured lead pose
  std::deque<Eigen::Vector2d> recent_positions_;  // for v_lead, one per step (held if lost)
};

}  // namespace unseen
