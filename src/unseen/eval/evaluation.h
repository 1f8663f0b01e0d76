// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Scoring a pose stream against ground truth.
//
// Definitions (all poses are world_from_obj):
//  * Position error: t_est - t_gt, the difference of the object origins in the world frame,
//    per axis in millimetres; its norm is the 3-D distance.
//  * Orientation error: the rotation vector of R_gt^T R_est (SO(3) log), i.e. the rotation
//    that takes the true object frame to the estimated one, expressed in the object frame,
//    per axis in degrees; its norm is the total angle in [0, 180] degrees. (With
//    `rotation_error_in_world` it is the rotation vector of R_est R_gt^T, in the world
//    frame; the total angle is the same.)
//  * Success (the RBOT criterion): a frame succeeds when it has a pose that is not reported
//    lost and both the 3-D distance < 5 cm and the angle < 5 degrees (2 cm / 2 degrees for
//    the strict rate). Frames reported lost or searching, and frames missing from the
//    stream, count as failures. Success rates are fractions in [0, 1] of the frames that
//    have ground truth.
//  * Error statistics (mean, RMS, max) are taken over the "scored" frames only: frames
//    with ground truth and a pose whose status is `tracking`. Per-axis statistics use the
//    absolute value of each component.
//  * The first failure frame is the id of the first frame (in sequence order) that has
//    ground truth and does not succeed at 5 cm / 5 degrees, or -1.
//  * Frames per second: (number of records carrying process_ms) / (sum of their
//    process_ms in seconds), over every record of the stream; absent when no record
//    carries timing (or their sum is 0).
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "unseen/geometry/rigid3.h"
#include "unseen/io/pose_stream.h"

namespace unseen {

struct EvaluationOptions {
  // Remove the fixed offset between the estimated and the true object frame at the first
  // scored frame (for unknown objects whose frame the system chose):
  // obj_gt_from_obj_est = gt0^-1 * est0, then every estimate becomes est * offset^-1.
  bool align_first = false;
  double success_trans_m = 0.05;         // RBOT threshold on the 3-D distance, metres (> 0)
  double success_rot_deg = 5.0;          // RBOT threshold on the angle, degrees (> 0)
  double strict_trans_m = 0.02;          // strict threshold on the 3-D distance, metres (> 0)
  double strict_rot_deg = 2.0;           // strict threshold on the angle, degrees (> 0)
  bool rotation_error_in_world = false;  // per-axis rotation error in the world frame
  void Check() const;
};

// Ground truth of one frame of a sequence, in sequence order.
struct GroundTruthFrame {
  int frame = 0;                          // frame id (matches PoseRecord::frame)
  std::optional<Rigid3d> world_from_obj;  // nullopt: this frame is not scored
};

// Error of one frame that has ground truth.
struct FrameError {
  int frame = 0;                            // frame id
  bool has_pose = false;                    // the stream has a record for this frame
  TrackStatus status = TrackStatus::kLost;  // of the record (kLost when missing)
  double confidence = 0.0;                  // of the record (0 when missing)
  bool scored = false;  // has_pose && status == kTracking: errors below are valid
  Eigen::Vector3d trans_err_mm = Eigen::Vector3d::Zero();  // t_est - t_gt, world, mm
  double trans_err_norm_mm = 0.0;                          // |trans_err_mm|
  Eigen::Vector3d rot_err_deg = Eigen::Vector3d::Zero();   // rotation vector, degrees
  double rot_err_angle_deg = 0.0;                          // |rot_err_deg|, [0, 180]
  bool success = false;         // scored and within success_trans_m / success_rot_deg
  bool strict_success = false;  // scored and within strict_trans_m / strict_rot_deg
};

// Mean, RMS and max of a non-negative error over the scored frames.
struct ErrorStats {
  double mean = 0.0;
  double rms = 0.0;
  double max = 0.0;
};

struct EvaluationResult {
  EvaluationOptions options;
  std::vector<FrameError> per_frame;  // one per frame with ground truth, sequence order
  int frames = 0;                     // frames with ground truth
  int scored_frames = 0;              // of those, with a `tracking` pose
  int lost_frames = 0;                // of those, with a record whose status is lost or searching
  int missing_frames = 0;             // of those, without a record in the stream
  int extra_records = 0;              // records whose frame has no ground truth (ignored)
  double success_rate = 0.0;          // fraction at success_trans_m / success_rot_deg
  double strict_success_rate = 0.0;   // fraction at strict_trans_m / strict_rot_deg
  ErrorStats trans_err_mm;            // 3-D distance, mm
  ErrorStats trans_err_axis_mm[3];    // |x|, |y|, |z|, mm
  ErrorStats rot_err_deg;             // total angle, degrees
  ErrorStats rot_err_axis_deg[3];     // |x|, |y|, |z| of the rotation vector, degrees
  int first_failure_frame = -1;       // frame id, or -1 when every frame succeeds
  std::optional<double> fps;          // from process_ms, when the stream carries it
  std::optional<Rigid3d> obj_gt_from_obj_est;  // the offset removed by align_first

  // The summary table (several lines, for people).
  std::string Table() const;
  // One JSON object with the keys: frames, scored_frames, lost_frames, missing_frames,
  // extra_records, success_5cm5deg and success_2cm2deg (fractions in [0, 1] at the
  // options' thresholds, which success_thresholds repeats), mean/rms/max_trans_err_mm,
  // mean/rms/max_trans_err_mm_xyz ([x, y, z] of |error|), mean/rms/max_rot_err_deg,
  // mean/rms/max_rot_err_deg_xyz, rot_err_frame ("object" or "world"),
  // first_failure_frame (-1 when never), fps, align_first, alignment_offset
  // (obj_gt_from_obj_est as {"t": metres, "q": [x, y, z, w]}, or null). Statistics are
  // null when no frame was scored; fps is null when the stream carries no timing.
  nlohmann::json ToJson() const;
};

// Scores `poses` against `ground_truth`, matching them by frame id. Throws unseen::Error
// when `poses` has two records for the same frame, a record's pose is invalid (NaN,
// non-unit quaternion), ground truth repeats a frame id, or no frame has ground truth.
// With align_first and no scored frame, no offset is removed.
EvaluationResult Evaluate(const std::vector<GroundTruthFrame>& ground_truth,
                          const std::vector<PoseRecord>& poses,
                          const EvaluationOptions& options = {});

// Writes one CSV line per frame with ground truth: frame, status, confidence, scored,
// ex_mm, ey_mm, ez_mm, e_mm, rx_deg, ry_deg, rz_deg, r_deg, success_5cm5deg,
// success_2cm2deg (errors empty when the frame is not scored). Throws unseen::Error when
// the file cannot be written.
void WritePerFrameCsv(const std::string& path, const EvaluationResult& result);

}  // namespace unseen
