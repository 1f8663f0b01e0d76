// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Object trajectories for synthetic sequences (SPEC 8): world_from_obj as a function of
// time. Frame k of a sequence at `fps` is shown at t = k / fps seconds.
//
//  * WaypointTrajectory: a polyline of waypoints (relative to an origin) travelled at a
//    constant speed, an initial rotation and a constant spin; SPEC 8's Fig. 4.7 zig-zag and
//    Fig. 3.12 path. The thesis states the speeds of Table 4.3 as "initial velocities"
//    (30, 15) ... (480, 240) mm/s in the top view; here such a velocity is travelled as the
//    constant path speed |v| (e.g. (120, 60) mm/s -> 134.2 mm/s, the thesis's "approximately
//    134 mm/s").
//  * KeyframeTrajectory: poses at given times (e.g. a pose stream file) interpolated
//    linearly in translation and by slerp in rotation, held before the first and after the
//    last key.
//  * StaticTrajectory: one fixed pose.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "unseen/geometry/rigid3.h"

namespace unseen {

// A rotation of `angle_deg` degrees about `axis` (any non-zero length).
struct AxisRotation {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitY();
  double angle_deg = 0.0;
};

// The rotation of applying `steps` in order, each about the object's own axes as turned by
// the steps before it (intrinsic rotations): R = R_1 R_2 ... R_n. This is the convention
// of the development sequences' scene.json ("initial_rotation": x 20 deg then y 30 deg is
// Rx(20) Ry(30)). Throws unseen::Error naming `what` for a zero or non-finite axis or
// a non-finite angle.
Eigen::Quaterniond ComposeRotations(const std::vector<AxisRotation>& steps,
                                    const std::string& what = "rotation");

// Constant rotation rate of an object.
struct SpinOptions {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitY();  // any non-zero length
  double rate_rad_s = 0.0;                          // signed, right-hand rule about axis
  // false: `axis` is fixed in the object (R(t) = R0 Exp(w t)); true: fixed in the world
  // (R(t) = Exp(w t) R0).
  bool world_frame = false;
  void Check() const;
};

// world_from_obj(t). Implementations are immutable and thread-safe.
class Trajectory {
 public:
  virtual ~Trajectory() = default;
  // The pose at time `t_s` seconds (any finite t; before the start and after the end the
  // motion is held as each implementation documents).
  virtual Rigid3d WorldFromObj(double t_s) const = 0;
  // Seconds at which the motion ends; +infinity when it never ends (a pure spin).
  virtual double EndTimeS() const = 0;
};

class StaticTrajectory : public Trajectory {
 public:
  // Throws unseen::Error when the pose is not valid (NaN, non-unit rotation).
  explicit StaticTrajectory(const Rigid3d& world_from_obj);
  Rigid3d WorldFromObj(double t_s) const override { return world_from_obj_; }
  double EndTimeS() const override { return 0.0; }

 private:
  Rigid3d world_from_obj_;
};

struct WaypointTrajectoryOptions {
  Eigen::Vector3d origin_m = Eigen::Vector3d(0.0, 0.0, 1.0);  // world position of (0,0,0)
  // Positions relative to `origin_m`, metres, travelled in order; at least one. The first
  // is the start position. Consecutive duplicates are allowed (zero-length segments).
  std::vector<Eigen::Vector3d> waypoints_m = {Eigen::Vector3d::Zero()};
  double speed_m_s = 0.04;    // constant speed along the polyline, m/s (> 0)
  double start_time_s = 0.0;  // the object waits at the first waypoint until then
  Eigen::Quaterniond initial_rotation = Eigen::Quaterniond::Identity();  // world_from_obj at t=0
  SpinOptions spin;  // spin starts at t = 0 and never stops
  // Throws unseen::Error naming `what` and the offending field.
  void Check(const std::string& what = "waypoint trajectory") const;
};

// Constant-speed travel along a polyline with a constant spin. The position is held at the
// last waypoint after EndTimeS() (the spin continues, as a turntable would).
class WaypointTrajectory : public Trajectory {
 public:
  // Throws unseen::Error (via options.Check()) for invalid options.
  explicit WaypointTrajectory(const WaypointTrajectoryOptions& options);
  Rigid3d WorldFromObj(double t_s) const override;
  // start_time_s + PathLengthM() / speed_m_s.
  double EndTimeS() const override;

  // Length of the polyline, metres.
  double PathLengthM() const { return cumulative_m_.back(); }
  // World position at arc length `s_m` along the path (clamped to [0, PathLengthM()]).
  Eigen::Vector3d PositionAtArcLength(double s_m) const;
  // World rotation (world_from_obj) at time t, from the initial rotation and the spin.
  Eigen::Quaterniond RotationAt(double t_s) const;
  const WaypointTrajectoryOptions& options() const { return options_; }

 private:
  WaypointTrajectoryOptions options_;
  std::vector<double> cumulative_m_;  // arc length at each waypoint
};

// One timed pose.
struct PoseKey {
  double time_s = 0.0;
  Rigid3d world_from_obj;
};

// Interpolates between timed poses (translation linearly, rotation by slerp); holds the
// first pose before its time and the last after.
class KeyframeTrajectory : public Trajectory {
 public:
  // `keys` must be non-empty, with finite strictly increasing times and valid poses; throws
  // unseen::Error naming `what` and the offending key otherwise.
  KeyframeTrajectory(std::vector<PoseKey> keys, const std::string& what = "pose keys");
  Rigid3d WorldFromObj(double t_s) const override;
  double EndTimeS() const override { return keys_.back().time_s; }
  const std::vector<PoseKey>& keys() const { return keys_; }

 private:
  std::vector<PoseKey> keys_;
};

// Reads a pose stream (CSV or JSON lines, io/pose_stream.h) as keys. Records whose status
// is not "tracking" are skipped. Times are the records' time_s, unless they do not
// increase strictly, in which case frame / fps is used; `time_offset_s` is then added.
// Throws unseen::Error naming the file for an unreadable file or no usable record.
std::unique_ptr<KeyframeTrajectory> LoadPoseFileTrajectory(const std::string& path, double fps,
                                                           double time_offset_s = 0.0);

}  // namespace unseen
