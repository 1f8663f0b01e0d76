// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/eval/evaluation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>

#include "unseen/util/error.h"

namespace unseen {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

bool IsFinitePositive(double v) { return std::isfinite(v) && v > 0.0; }

// Accumulates mean, RMS and max of non-negative values.
class StatsAccumulator {
 public:
  void Add(double v) {
    ++n_;
    sum_ += v;
    sum_sq_ += v * v;
    max_ = std::max(max_, v);
  }
  ErrorStats Get() const {
    ErrorStats s;
    if (n_ == 0) return s;
    s.mean = sum_ / n_;
    s.rms = std::sqrt(sum_sq_ / n_);
    s.max = max_;
    return s;
  }

 private:
  int n_ = 0;
  double sum_ = 0.0, sum_sq_ = 0.0, max_ = 0.0;
};

nlohmann::json ValueOrNull(double v, bool valid) {
  return valid ? nlohmann::json(v) : nlohmann::json(nullptr);
}

nlohmann::json AxisJson(const ErrorStats (&axes)[3], double ErrorStats::*member, bool valid) {
  if (!valid) return nullptr;
  return nlohmann::json::array({axes[0].*member, axes[1].*member, axes[2].*member});
}

}  // namespace

void EvaluationOptions::Check() const {
  UNSEEN_CHECK(IsFinitePositive(success_trans_m),
               "EvaluationOptions: success_trans_m must be > 0 metres, got {}", success_trans_m);
  UNSEEN_CHECK(IsFinitePositive(success_rot_deg),
               "EvaluationOptions: success_rot_deg must be > 0 degrees, got {}", success_rot_deg);
  UNSEEN_CHECK(IsFinitePositive(strict_trans_m),
               "EvaluationOptions: strict_trans_m must be > 0 metres, got {}", strict_trans_m);
  UNSEEN_CHECK(IsFinitePositive(strict_rot_deg),
               "EvaluationOptions: strict_rot_deg must be > 0 degrees, got {}", strict_rot_deg);
}

EvaluationResult Evaluate(const std::vector<GroundTruthFrame>& ground_truth,
                          const std::vector<PoseRecord>& poses, const EvaluationOptions& options) {
  options.Check();
  EvaluationResult result;
  result.options = options;

  // Index the stream by frame id.
  std::map<int, const PoseRecord*> by_frame;
  for (size_t i = 0; i < poses.size(); ++i) {
    const PoseRecord& r = poses[i];
    UNSEEN_CHECK(by_frame.emplace(r.frame, &r).second,
                 "pose stream: frame {} appears more than once (record {})", r.frame, i);
    if (r.status == TrackStatus::kTracking) {
      UNSEEN_CHECK(r.world_from_obj.IsValid(),
                   "pose stream: frame {} has an invalid pose {} (NaN or non-unit quaternion)",
                   r.frame, r.world_from_obj.ToString());
    }
  }

  // Frames with ground truth, in order; ids must be unique.
  std::set<int> gt_ids;
  std::vector<const GroundTruthFrame*> gt_frames;
  for (const GroundTruthFrame& g : ground_truth) {
    UNSEEN_CHECK(gt_ids.insert(g.frame).second, "ground truth: frame {} appears more than once",
                 g.frame);
    if (!g.world_from_obj) continue;
    UNSEEN_CHECK(g.world_from_obj->IsValid(), "ground truth: frame {} has an invalid pose {}",
                 g.frame, g.world_from_obj->ToString());
    gt_frames.push_back(&g);
  }
  UNSEEN_CHECK(!gt_frames.empty(), "ground truth: no frame has a ground-truth pose");

  std::set<int> scored_ids;
  for (const GroundTruthFrame* g : gt_frames) scored_ids.insert(g->frame);
  for (const auto& [frame, record] : by_frame) result.extra_records += !scored_ids.count(frame);

  // Offset for align_first, from the first scored frame.
  Rigid3d obj_est_from_obj_gt;  // offset^-1
  if (options.align_first) {
    for (const GroundTruthFrame* g : gt_frames) {
      auto it = by_frame.find(g->frame);
      if (it == by_frame.end() || it->second->status != TrackStatus::kTracking) continue;
      const Rigid3d obj_gt_from_obj_est = g->world_from_obj->Inverse() * it->second->world_from_obj;
      result.obj_gt_from_obj_est = obj_gt_from_obj_est;
      obj_est_from_obj_gt = obj_gt_from_obj_est.Inverse();
      break;
    }
  }

  StatsAccumulator trans, rot, trans_axis[3], rot_axis[3];
  int successes = 0, strict_successes = 0;
  for (const GroundTruthFrame* g : gt_frames) {
    FrameError e;
    e.frame = g->frame;
    auto it = by_frame.find(g->frame);
    if (it == by_frame.end()) {
      ++result.missing_frames;
    } else {
      const PoseRecord& r = *it->second;
      e.has_pose = true;
      e.status = r.status;
      e.confidence = r.confidence;
      e.scored = r.status == TrackStatus::kTracking;
      if (!e.scored) ++result.lost_frames;
    }
    if (e.scored) {
      const Rigid3d& gt = *g->world_from_obj;
      Rigid3d est = it->second->world_from_obj;
      if (options.align_first) est = est * obj_est_from_obj_gt;
      e.trans_err_mm = (est.translation() - gt.translation()) * 1000.0;
      e.trans_err_norm_mm = e.trans_err_mm.norm();
      const Eigen::Quaterniond delta = options.rotation_error_in_world
                                           ? est.rotation() * gt.rotation().conjugate()
                                           : gt.rotation().conjugate() * est.rotation();
      e.rot_err_deg = LogSO3(delta.normalized()) * kRadToDeg;
      e.rot_err_angle_deg = e.rot_err_deg.norm();
      e.success = e.trans_err_norm_mm < options.success_trans_m * 1000.0 &&
                  e.rot_err_angle_deg < options.success_rot_deg;
      e.strict_success = e.trans_err_norm_mm < options.strict_trans_m * 1000.0 &&
                         e.rot_err_angle_deg < options.strict_rot_deg;
      ++result.scored_frames;
      trans.Add(e.trans_err_norm_mm);
      rot.Add(e.rot_err_angle_deg);
      for (int a = 0; a < 3; ++a) {
        trans_axis[a].Add(std::abs(e.trans_err_mm[a]));
        rot_axis[a].Add(std::abs(e.rot_err_deg[a]));
      }
    }
    successes += e.success;
    strict_successes += e.strict_success;
    if (!e.success && result.first_failure_frame < 0) result.first_failure_frame = e.frame;
    result.per_frame.push_back(e);
  }

  result.frames = static_cast<int>(gt_frames.size());
  result.success_rate = double(successes) / result.frames;
  result.strict_success_rate = double(strict_successes) / result.frames;
  result.trans_err_mm = trans.Get();
  result.rot_err_deg = rot.Get();
  for (int a = 0; a < 3; ++a) {
    result.trans_err_axis_mm[a] = trans_axis[a].Get();
    result.rot_err_axis_deg[a] = rot_axis[a].Get();
  }

  int timed = 0;
  double total_ms = 0.0;
  for (const PoseRecord& r : poses) {
    if (!r.process_ms) continue;
    UNSEEN_CHECK(std::isfinite(*r.process_ms) && *r.process_ms >= 0.0,
                 "pose stream: frame {} has invalid process_ms {}", r.frame, *r.process_ms);
    ++timed;
    total_ms += *r.process_ms;
  }
  if (timed > 0 && total_ms > 0.0) result.fps = timed / (total_ms / 1000.0);
  return result;
}

std::string EvaluationResult::Table() const {
  const bool valid = scored_frames > 0;
  std::string s;
  s += fmt::format("frames with ground truth  {:>8}\n", frames);
  s += fmt::format("  tracked (scored)        {:>8}\n", scored_frames);
  s += fmt::format("  lost / searching        {:>8}\n", lost_frames);
  s += fmt::format("  missing from stream     {:>8}\n", missing_frames);
  if (extra_records > 0) {
    s += fmt::format("records without ground truth {:>5} (ignored)\n", extra_records);
  }
  s += fmt::format("success {:g} cm / {:g} deg     {:>7.2f} %\n", options.success_trans_m * 100.0,
                   options.success_rot_deg, success_rate * 100.0);
  s += fmt::format("success {:g} cm / {:g} deg     {:>7.2f} %\n", options.strict_trans_m * 100.0,
                   options.strict_rot_deg, strict_success_rate * 100.0);
  s += fmt::format("first failure frame       {:>8}\n", first_failure_frame);
  s += fmt::format("fps                       {:>8}\n", fps ? fmt::format("{:.1f}", *fps) : "n/a");
  if (obj_gt_from_obj_est) {
    const double angle = LogSO3(obj_gt_from_obj_est->rotation()).norm() * kRadToDeg;
    s += fmt::format("aligned at first frame: offset {:.1f} mm, {:.2f} deg\n",
                     obj_gt_from_obj_est->translation().norm() * 1000.0, angle);
  }
  s += fmt::format("\n{:<22}{:>10}{:>10}{:>10}\n", "error", "mean", "rms", "max");
  auto row = [&](const std::string& name, const ErrorStats& st) {
    if (valid) {
      s += fmt::format("{:<22}{:>10.3f}{:>10.3f}{:>10.3f}\n", name, st.mean, st.rms, st.max);
    } else {
      s += fmt::format("{:<22}{:>10}{:>10}{:>10}\n", name, "-", "-", "-");
    }
  };
  const char* axes = "xyz";
  row("position (mm)", trans_err_mm);
  for (int a = 0; a < 3; ++a) row(fmt::format("  |{}| (mm)", axes[a]), trans_err_axis_mm[a]);
  row("orientation (deg)", rot_err_deg);
  for (int a = 0; a < 3; ++a) {
    row(fmt::format("  |{}| (deg, {})", axes[a], options.rotation_error_in_world ? "world" : "obj"),
        rot_err_axis_deg[a]);
  }
  return s;
}

nlohmann::json EvaluationResult::ToJson() const {
  const bool valid = scored_frames > 0;
  nlohmann::json j;
  j["frames"] = frames;
  j["scored_frames"] = scored_frames;
  j["lost_frames"] = lost_frames;
  j["missing_frames"] = missing_frames;
  j["extra_records"] = extra_records;
  j["success_5cm5deg"] = success_rate;
  j["success_2cm2deg"] = strict_success_rate;
  j["success_thresholds"] = {{"trans_m", options.success_trans_m},
                             {"rot_deg", options.success_rot_deg},
                             {"strict_trans_m", options.strict_trans_m},
                             {"strict_rot_deg", options.strict_rot_deg}};
  j["mean_trans_err_mm"] = ValueOrNull(trans_err_mm.mean, valid);
  j["rms_trans_err_mm"] = ValueOrNull(trans_err_mm.rms, valid);
  j["max_trans_err_mm"] = ValueOrNull(trans_err_mm.max, valid);
  j["mean_trans_err_mm_xyz"] = AxisJson(trans_err_axis_mm, &ErrorStats::mean, valid);
  j["rms_trans_err_mm_xyz"] = AxisJson(trans_err_axis_mm, &ErrorStats::rms, valid);
  j["max_trans_err_mm_xyz"] = AxisJson(trans_err_axis_mm, &ErrorStats::max, valid);
  j["mean_rot_err_deg"] = ValueOrNull(rot_err_deg.mean, valid);
  j["rms_rot_err_deg"] = ValueOrNull(rot_err_deg.rms, valid);
  j["max_rot_err_deg"] = ValueOrNull(rot_err_deg.max, valid);
  j["mean_rot_err_deg_xyz"] = AxisJson(rot_err_axis_deg, &ErrorStats::mean, valid);
  j["rms_rot_err_deg_xyz"] = AxisJson(rot_err_axis_deg, &ErrorStats::rms, valid);
  j["max_rot_err_deg_xyz"] = AxisJson(rot_err_axis_deg, &ErrorStats::max, valid);
  j["rot_err_frame"] = options.rotation_error_in_world ? "world" : "object";
  j["first_failure_frame"] = first_failure_frame;
  j["fps"] = fps ? nlohmann::json(*fps) : nlohmann::json(nullptr);
  j["align_first"] = options.align_first;
  if (obj_gt_from_obj_est) {
    const auto& q = obj_gt_from_obj_est->rotation();
    const auto& t = obj_gt_from_obj_est->translation();
    j["alignment_offset"] = {{"t", {t.x(), t.y(), t.z()}}, {"q", {q.x(), q.y(), q.z(), q.w()}}};
  } else {
    j["alignment_offset"] = nullptr;
  }
  return j;
}

void WritePerFrameCsv(const std::string& path, const EvaluationResult& result) {
  std::ofstream out(path);
  UNSEEN_CHECK(out.good(), "per-frame CSV '{}': cannot create the file", path);
  out << "frame,status,confidence,scored,ex_mm,ey_mm,ez_mm,e_mm,rx_deg,ry_deg,rz_deg,r_deg,"
         "success_5cm5deg,success_2cm2deg\n";
  for (const FrameError& e : result.per_frame) {
    out << e.frame << ',' << (e.has_pose ? ToString(e.status) : "missing") << ','
        << fmt::format("{:.4f}", e.confidence) << ',' << int(e.scored) << ',';
    if (e.scored) {
      out << fmt::format("{:.4f},{:.4f},{:.4f},{:.4f},{:.5f},{:.5f},{:.5f},{:.5f},",
                         e.trans_err_mm.x(), e.trans_err_mm.y(), e.trans_err_mm.z(),
                         e.trans_err_norm_mm, e.rot_err_deg.x(), e.rot_err_deg.y(),
                         e.rot_err_deg.z(), e.rot_err_angle_deg);
    } else {
      out << ",,,,,,,,";
    }
    out << int(e.success) << ',' << int(e.strict_success) << '\n';
  }
  out.flush();
  UNSEEN_CHECK(out.good(), "per-frame CSV '{}': write failed", path);
}

}  // namespace unseen
