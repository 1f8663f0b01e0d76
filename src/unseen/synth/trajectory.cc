// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/synth/trajectory.h"

#include <algorithm>
#include <cmath>

#include "unseen/io/pose_stream.h"
#include "unseen/util/error.h"

namespace unseen {

namespace {

std::string VecStr(const Eigen::Vector3d& v) {
  return fmt::format("[{} {} {}]", v.x(), v.y(), v.z());
}

}  // namespace

Eigen::Quaterniond ComposeRotations(const std::vector<AxisRotation>& steps,
                                    const std::string& what) {
  Eigen::Quaterniond r = Eigen::Quaterniond::Identity();
  for (size_t i = 0; i < steps.size(); ++i) {
    const AxisRotation& step = steps[i];
    const double n = step.axis.norm();
    UNSEEN_CHECK(step.axis.allFinite() && n > 1e-12, "{}: step {} has a zero or non-finite axis {}",
                 what, i, VecStr(step.axis));
    UNSEEN_CHECK(std::isfinite(step.angle_deg), "{}: step {} has a non-finite angle {}", what, i,
                 step.angle_deg);
    const Eigen::Vector3d w = step.axis / n * (step.angle_deg * M_PI / 180.0);
    r = r * ExpSO3(w);
  }
  return r.normalized();
}

void SpinOptions::Check() const {
  UNSEEN_CHECK(axis.allFinite() && axis.norm() > 1e-12, "spin axis {} is zero or not finite",
               VecStr(axis));
  UNSEEN_CHECK(std::isfinite(rate_rad_s), "spin rate {} rad/s is not finite", rate_rad_s);
}

StaticTrajectory::StaticTrajectory(const Rigid3d& world_from_obj)
    : world_from_obj_(world_from_obj) {
  UNSEEN_CHECK(world_from_obj.IsValid(), "static pose {} is not a valid pose",
               world_from_obj.ToString());
}

void WaypointTrajectoryOptions::Check(const std::string& what) const {
  UNSEEN_CHECK(origin_m.allFinite(), "{}: origin {} is not finite", what, VecStr(origin_m));
  UNSEEN_CHECK(!waypoints_m.empty(), "{}: needs at least one waypoint", what);
  for (size_t i = 0; i < waypoints_m.size(); ++i) {
    UNSEEN_CHECK(waypoints_m[i].allFinite(), "{}: waypoint {} {} is not finite", what, i,
                 VecStr(waypoints_m[i]));
  }
  UNSEEN_CHECK(std::isfinite(speed_m_s) && speed_m_s > 0.0,
               "{}: speed {} m/s must be positive and finite", what, speed_m_s);
  UNSEEN_CHECK(std::isfinite(start_time_s), "{}: start time {} s is not finite", what,
               start_time_s);
  UNSEEN_CHECK(
      initial_rotation.coeffs().allFinite() && std::abs(initial_rotation.norm() - 1.0) < 1e-6,
      "{}: initial rotation is not a unit quaternion", what);
  try {
    spin.Check();
  } catch (const Error& e) {
    ThrowError("{}: {}", what, e.what());
  }
}

WaypointTrajectory::WaypointTrajectory(const WaypointTrajectoryOptions& options)
    : options_(options) {
  options_.Check();
  cumulative_m_.reserve(options_.waypoints_m.size());
  cumulative_m_.push_back(0.0);
  for (size_t i = 1; i < options_.waypoints_m.size(); ++i) {
    cumulative_m_.push_back(cumulative_m_.back() +
                            (options_.waypoints_m[i] - options_.waypoints_m[i - 1]).norm());
  }
}

double WaypointTrajectory::EndTimeS() const {
  return options_.start_time_s + PathLengthM() / options_.speed_m_s;
}

Eigen::Vector3d WaypointTrajectory::PositionAtArcLength(double s_m) const {
  const auto& w = options_.waypoints_m;
  if (w.size() == 1 || !(s_m > 0.0)) return options_.origin_m + w.front();
  if (s_m >= PathLengthM()) return options_.origin_m + w.back();
  // First waypoint whose arc length exceeds s: the segment ends there.
  const auto it = std::upper_bound(cumulative_m_.begin(), cumulative_m_.end(), s_m);
  const size_t end = static_cast<size_t>(it - cumulative_m_.begin());
  const double seg = cumulative_m_[end] - cumulative_m_[end - 1];
  const double a = seg > 0.0 ? (s_m - cumulative_m_[end - 1]) / seg : 0.0;
  return options_.origin_m + w[end - 1] + a * (w[end] - w[end - 1]);
}

Eigen::Quaterniond WaypointTrajectory::RotationAt(double t_s) const {
  const SpinOptions& spin = options_.spin;
  const Eigen::Quaterniond step = ExpSO3(spin.axis.normalized() * (spin.rate_rad_s * t_s));
  const Eigen::Quaterniond r =
      spin.world_frame ? step * options_.initial_rotation : options_.initial_rotation * step;
  return r.normalized();
}

Rigid3d WaypointTrajectory::WorldFromObj(double t_s) const {
  const double s = options_.speed_m_s * (t_s - options_.start_time_s);
  return Rigid3d(RotationAt(t_s), PositionAtArcLength(s));
}

KeyframeTrajectory::KeyframeTrajectory(std::vector<PoseKey> keys, const std::string& what)
    : keys_(std::move(keys)) {
  UNSEEN_CHECK(!keys_.empty(), "{}: no poses", what);
  for (size_t i = 0; i < keys_.size(); ++i) {
    UNSEEN_CHECK(std::isfinite(keys_[i].time_s), "{}: key {} has a non-finite time {}", what, i,
                 keys_[i].time_s);
    UNSEEN_CHECK(keys_[i].world_from_obj.IsValid(), "{}: key {} (t = {} s) has an invalid pose {}",
                 what, i, keys_[i].time_s, keys_[i].world_from_obj.ToString());
    if (i > 0) {
      UNSEEN_CHECK(keys_[i].time_s > keys_[i - 1].time_s,
                   "{}: key {} time {} s does not increase (previous {} s)", what, i,
                   keys_[i].time_s, keys_[i - 1].time_s);
    }
  }
}

Rigid3d KeyframeTrajectory::WorldFromObj(double t_s) const {
  if (t_s <= keys_.front().time_s) return keys_.front().world_from_obj;
  if (t_s >= keys_.back().time_s) return keys_.back().world_from_obj;
  const auto it = std::upper_bound(keys_.begin(), keys_.end(), t_s,
                                   [](double t, const PoseKey& k) { return t < k.time_s; });
  const PoseKey& b = *it;
  const PoseKey& a = *(it - 1);
  const double u = (t_s - a.time_s) / (b.time_s - a.time_s);
  return Rigid3d::Interpolate(a.world_from_obj, b.world_from_obj, u);
}

std::unique_ptr<KeyframeTrajectory> LoadPoseFileTrajectory(const std::string& path, double fps,
                                                           double time_offset_s) {
  UNSEEN_CHECK(std::isfinite(fps) && fps > 0.0, "pose file {}: fps {} must be positive", path, fps);
  const std::vector<PoseRecord> records = ReadPoseStream(path);
  std::vector<const PoseRecord*> usable;
  for (const PoseRecord& r : records) {
    if (r.status == TrackStatus::kTracking) usable.push_back(&r);
  }
  UNSEEN_CHECK(!usable.empty(), "pose file {}: no record with status \"tracking\" ({} records)",
               path, records.size());
  bool times_increase = true;
  for (size_t i = 1; i < usable.size(); ++i) {
    times_increase = times_increase && usable[i]->time_s > usable[i - 1]->time_s;
  }
  std::vector<PoseKey> keys;
  keys.reserve(usable.size());
  for (const PoseRecord* r : usable) {
    const double t = times_increase ? r->time_s : r->frame / fps;
    keys.push_back({t + time_offset_s, r->world_from_obj});
  }
  return std::make_unique<KeyframeTrajectory>(std::move(keys), "pose file " + path);
}

}  // namespace unseen
