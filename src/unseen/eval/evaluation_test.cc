// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/eval/evaluation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "unseen/eval/test_sequence.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

// A smooth trajectory with varied rotations, frames 0..n-1.
std::vector<GroundTruthFrame> MakeGroundTruth(int n) {
  std::vector<GroundTruthFrame> gt;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d w(0.3 + 0.05 * i, -0.2 + 0.03 * i, 0.1 * i);
    const Eigen::Vector3d t(0.1 * std::sin(0.2 * i), 0.02 * i, 1.0 + 0.01 * i);
    gt.push_back({i, Rigid3d(ExpSO3(w), t)});
  }
  return gt;
}

TEST(Evaluation, GroundTruthAgainstItselfIsZeroError) {
  const auto gt = MakeGroundTruth(30);
  const EvaluationResult r = Evaluate(gt, testing::PerfectPoseStream(gt));
  EXPECT_EQ(r.frames, 30);
  EXPECT_EQ(r.scored_frames, 30);
  EXPECT_EQ(r.lost_frames, 0);
  EXPECT_EQ(r.missing_frames, 0);
  EXPECT_DOUBLE_EQ(r.success_rate, 1.0);
  EXPECT_DOUBLE_EQ(r.strict_success_rate, 1.0);
  EXPECT_NEAR(r.trans_err_mm.max, 0.0, 1e-9);
  EXPECT_NEAR(r.rot_err_deg.max, 0.0, 1e-6);
  EXPECT_EQ(r.first_failure_frame, -1);
  EXPECT_FALSE(r.fps.has_value());
  ASSERT_EQ(r.per_frame.size(), 30u);
}

TEST(Evaluation, ConstantTranslationOffsetGivesKnownError) {
  const auto gt = MakeGroundTruth(25);
  auto poses = testing::PerfectPoseStream(gt);
  for (PoseRecord& p : poses) {
    p.world_from_obj.set_translation(p.world_from_obj.translation() + Eigen::Vector3d(0.010, 0, 0));
  }
  const EvaluationResult r = Evaluate(gt, poses);
  EXPECT_NEAR(r.trans_err_mm.mean, 10.0, 1e-9);
  EXPECT_NEAR(r.trans_err_mm.rms, 10.0, 1e-9);
  EXPECT_NEAR(r.trans_err_mm.max, 10.0, 1e-9);
  EXPECT_NEAR(r.trans_err_axis_mm[0].mean, 10.0, 1e-9);
  EXPECT_NEAR(r.trans_err_axis_mm[1].max, 0.0, 1e-9);
  EXPECT_NEAR(r.trans_err_axis_mm[2].max, 0.0, 1e-9);
  EXPECT_NEAR(r.per_frame[3].trans_err_mm.x(), 10.0, 1e-9);  // signed: estimate - truth
  EXPECT_NEAR(r.rot_err_deg.max, 0.0, 1e-6);
  EXPECT_DOUBLE_EQ(r.success_rate, 1.0);         // 1 cm < 5 cm
  EXPECT_DOUBLE_EQ(r.strict_success_rate, 1.0);  // 1 cm < 2 cm
}

TEST(Evaluation, RotationAboutObjectZGivesKnownError) {
  const auto gt = MakeGroundTruth(20);
  auto poses = testing::PerfectPoseStream(gt);
  const Rigid3d rot_z(ExpSO3(Eigen::Vector3d(0, 0, 3.0 * kDegToRad)), Eigen::Vector3d::Zero());
  for (PoseRecord& p : poses) p.world_from_obj = p.world_from_obj * rot_z;  // in the object frame
  const EvaluationResult r = Evaluate(gt, poses);
  EXPECT_NEAR(r.rot_err_deg.mean, 3.0, 1e-9);
  EXPECT_NEAR(r.rot_err_deg.max, 3.0, 1e-9);
  EXPECT_NEAR(r.rot_err_axis_deg[2].mean, 3.0, 1e-9);
  EXPECT_NEAR(r.rot_err_axis_deg[0].max, 0.0, 1e-9);
  EXPECT_NEAR(r.rot_err_axis_deg[1].max, 0.0, 1e-9);
  EXPECT_NEAR(r.trans_err_mm.max, 0.0, 1e-9);    // rotation about the object origin
  EXPECT_DOUBLE_EQ(r.success_rate, 1.0);         // 3 deg < 5 deg
  EXPECT_DOUBLE_EQ(r.strict_success_rate, 0.0);  // 3 deg >= 2 deg
  EXPECT_EQ(r.first_failure_frame, -1);

  // In the world frame the same error is R_gt * (0, 0, 3 deg): same angle, other axes.
  EvaluationOptions world;
  world.rotation_error_in_world = true;
  const EvaluationResult rw = Evaluate(gt, poses, world);
  EXPECT_NEAR(rw.rot_err_deg.mean, 3.0, 1e-9);
  const Eigen::Vector3d expected = gt[5].world_from_obj->rotation() * Eigen::Vector3d(0, 0, 3.0);
  EXPECT_NEAR((rw.per_frame[5].rot_err_deg - expected).norm(), 0.0, 1e-9);
}

TEST(Evaluation, LostFramesCountAsFailuresButNotInErrorStats) {
  const auto gt = MakeGroundTruth(10);
  auto poses = testing::PerfectPoseStream(gt);
  // Frames 4 and 7 lost (with a wild pose that must not enter the statistics); 8 searching.
  for (int f : {4, 7}) {
    poses[f].status = TrackStatus::kLost;
    poses[f].world_from_obj.set_translation(Eigen::Vector3d(5, 5, 5));
  }
  poses[8].status = TrackStatus::kSearching;
  const EvaluationResult r = Evaluate(gt, poses);
  EXPECT_EQ(r.frames, 10);
  EXPECT_EQ(r.lost_frames, 3);
  EXPECT_EQ(r.scored_frames, 7);
  EXPECT_DOUBLE_EQ(r.success_rate, 0.7);
  EXPECT_DOUBLE_EQ(r.strict_success_rate, 0.7);
  EXPECT_NEAR(r.trans_err_mm.max, 0.0, 1e-9);
  EXPECT_EQ(r.first_failure_frame, 4);
  EXPECT_FALSE(r.per_frame[4].scored);
  EXPECT_FALSE(r.per_frame[4].success);
  EXPECT_EQ(r.per_frame[8].status, TrackStatus::kSearching);
}

TEST(Evaluation, MissingFramesCountAsFailures) {
  const auto gt = MakeGroundTruth(10);
  auto poses = testing::PerfectPoseStream(gt);
  poses.erase(poses.begin() + 6, poses.end());  // frames 6..9 missing
  poses.erase(poses.begin() + 2);               // frame 2 missing
  const EvaluationResult r = Evaluate(gt, poses);
  EXPECT_EQ(r.missing_frames, 5);
  EXPECT_EQ(r.scored_frames, 5);
  EXPECT_EQ(r.lost_frames, 0);
  EXPECT_DOUBLE_EQ(r.success_rate, 0.5);
  EXPECT_EQ(r.first_failure_frame, 2);
  EXPECT_FALSE(r.per_frame[2].has_pose);
}

TEST(Evaluation, FramesWithoutGroundTruthAreNotScored) {
  auto gt = MakeGroundTruth(10);
  auto poses = testing::PerfectPoseStream(gt);
  gt[3].world_from_obj.reset();
  poses[3].world_from_obj.set_translation(Eigen::Vector3d(9, 9, 9));
  const EvaluationResult r = Evaluate(gt, poses);
  EXPECT_EQ(r.frames, 9);
  EXPECT_EQ(r.extra_records, 1);
  EXPECT_DOUBLE_EQ(r.success_rate, 1.0);
}

TEST(Evaluation, FirstFailureFrameIsWhereErrorExceedsThreshold) {
  const auto gt = MakeGroundTruth(40);
  auto poses = testing::PerfectPoseStream(gt);
  // Drift of 2.1 mm per frame in y: 5 cm exceeded first at frame 24 (50.4 mm).
  for (PoseRecord& p : poses) {
    p.world_from_obj.set_translation(p.world_from_obj.translation() +
                                     Eigen::Vector3d(0, 0.0021 * p.frame, 0));
  }
  const EvaluationResult r = Evaluate(gt, poses);
  EXPECT_EQ(r.first_failure_frame, 24);
  EXPECT_DOUBLE_EQ(r.success_rate, 24.0 / 40.0);
  EXPECT_DOUBLE_EQ(r.strict_success_rate, 10.0 / 40.0);  // 0..9 under 20 mm
  EXPECT_NEAR(r.trans_err_mm.max, 2.1 * 39, 1e-9);
  EXPECT_NEAR(r.trans_err_mm.mean, 2.1 * 19.5, 1e-9);
  EXPECT_NEAR(r.trans_err_axis_mm[1].max, 2.1 * 39, 1e-9);
  double sum_sq = 0;
  for (int i = 0; i < 40; ++i) sum_sq += 2.1 * 2.1 * i * i;
  EXPECT_NEAR(r.trans_err_mm.rms, std::sqrt(sum_sq / 40), 1e-9);

  // A rotation beyond 5 deg fails too, with zero translation error.
  auto rotated = testing::PerfectPoseStream(gt);
  const Rigid3d rot(ExpSO3(Eigen::Vector3d(6.0 * kDegToRad, 0, 0)), Eigen::Vector3d::Zero());
  rotated[12].world_from_obj = rotated[12].world_from_obj * rot;
  EXPECT_EQ(Evaluate(gt, rotated).first_failure_frame, 12);
}

TEST(Evaluation, AlignFirstRemovesConstantOffsetExactly) {
  const auto gt = MakeGroundTruth(30);
  // The system chose its own object frame: est = gt * obj_gt_from_obj_est.
  const Rigid3d offset(ExpSO3(Eigen::Vector3d(0.4, -1.1, 2.0)), Eigen::Vector3d(0.03, -0.05, 0.08));
  auto poses = testing::PerfectPoseStream(gt);
  for (PoseRecord& p : poses) p.world_from_obj = p.world_from_obj * offset;

  const EvaluationResult raw = Evaluate(gt, poses);
  EXPECT_GT(raw.rot_err_deg.mean, 10.0);
  EXPECT_DOUBLE_EQ(raw.success_rate, 0.0);

  EvaluationOptions options;
  options.align_first = true;
  const EvaluationResult r = Evaluate(gt, poses, options);
  EXPECT_NEAR(r.trans_err_mm.max, 0.0, 1e-9);
  EXPECT_NEAR(r.rot_err_deg.max, 0.0, 1e-6);
  EXPECT_DOUBLE_EQ(r.success_rate, 1.0);
  ASSERT_TRUE(r.obj_gt_from_obj_est.has_value());
  EXPECT_NEAR((r.obj_gt_from_obj_est->translation() - offset.translation()).norm(), 0, 1e-12);
  EXPECT_NEAR(AngleBetween(r.obj_gt_from_obj_est->rotation(), offset.rotation()), 0, 1e-9);
}

TEST(Evaluation, AlignFirstSkipsLostLeadingFrames) {
  const auto gt = MakeGroundTruth(10);
  const Rigid3d offset(ExpSO3(Eigen::Vector3d(0, 0.5, 0)), Eigen::Vector3d(0.1, 0, 0));
  auto poses = testing::PerfectPoseStream(gt);
  for (PoseRecord& p : poses) p.world_from_obj = p.world_from_obj * offset;
  poses[0].status = TrackStatus::kSearching;
  poses[0].world_from_obj = Rigid3d();
  EvaluationOptions options;
  options.align_first = true;
  const EvaluationResult r = Evaluate(gt, poses, options);
  EXPECT_NEAR(r.trans_err_mm.max, 0.0, 1e-9);
  EXPECT_DOUBLE_EQ(r.success_rate, 0.9);
  EXPECT_EQ(r.first_failure_frame, 0);
}

TEST(Evaluation, FpsFromProcessTime) {
  const auto gt = MakeGroundTruth(4);
  auto poses = testing::PerfectPoseStream(gt);
  const double ms[] = {10.0, 20.0, 30.0, 40.0};  // 4 frames in 0.1 s
  for (int i = 0; i < 4; ++i) poses[i].process_ms = ms[i];
  const EvaluationResult r = Evaluate(gt, poses);
  ASSERT_TRUE(r.fps.has_value());
  EXPECT_NEAR(*r.fps, 40.0, 1e-9);
  EXPECT_NEAR(r.ToJson()["fps"].get<double>(), 40.0, 1e-9);

  poses[1].process_ms = -1.0;
  EXPECT_THROW(Evaluate(gt, poses), Error);
}

TEST(Evaluation, JsonHasKeysWithValues) {
  const auto gt = MakeGroundTruth(10);
  auto poses = testing::PerfectPoseStream(gt);
  for (PoseRecord& p : poses) {
    p.world_from_obj.set_translation(p.world_from_obj.translation() + Eigen::Vector3d(0, 0, 0.03));
  }
  poses[9].status = TrackStatus::kLost;
  const nlohmann::json j = Evaluate(gt, poses).ToJson();
  for (const char* key :
       {"frames", "lost_frames", "success_5cm5deg", "success_2cm2deg", "mean_trans_err_mm",
        "rms_trans_err_mm", "max_trans_err_mm", "mean_rot_err_deg", "max_rot_err_deg",
        "rms_rot_err_deg", "first_failure_frame", "fps", "mean_trans_err_mm_xyz",
        "mean_rot_err_deg_xyz", "max_rot_err_deg_xyz"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["frames"].get<int>(), 10);
  EXPECT_EQ(j["lost_frames"].get<int>(), 1);
  EXPECT_DOUBLE_EQ(j["success_5cm5deg"].get<double>(), 0.9);
  EXPECT_DOUBLE_EQ(j["success_2cm2deg"].get<double>(), 0.0);
  EXPECT_NEAR(j["mean_trans_err_mm"].get<double>(), 30.0, 1e-9);
  EXPECT_NEAR(j["rms_trans_err_mm"].get<double>(), 30.0, 1e-9);
  EXPECT_NEAR(j["max_trans_err_mm"].get<double>(), 30.0, 1e-9);
  EXPECT_NEAR(j["mean_trans_err_mm_xyz"][2].get<double>(), 30.0, 1e-9);
  EXPECT_NEAR(j["mean_rot_err_deg"].get<double>(), 0.0, 1e-6);
  EXPECT_EQ(j["first_failure_frame"].get<int>(), 9);
  EXPECT_TRUE(j["fps"].is_null());
  // Round trip through text.
  EXPECT_EQ(nlohmann::json::parse(j.dump()), j);
}

TEST(Evaluation, NoScoredFrameGivesNullStatistics) {
  const auto gt = MakeGroundTruth(3);
  const EvaluationResult r = Evaluate(gt, {});
  EXPECT_EQ(r.missing_frames, 3);
  EXPECT_DOUBLE_EQ(r.success_rate, 0.0);
  EXPECT_EQ(r.first_failure_frame, 0);
  const nlohmann::json j = r.ToJson();
  EXPECT_TRUE(j["mean_trans_err_mm"].is_null());
  EXPECT_TRUE(j["max_rot_err_deg"].is_null());
  EXPECT_NE(r.Table().find("missing from stream"), std::string::npos);
}

TEST(Evaluation, TableShowsFigures) {
  const auto gt = MakeGroundTruth(5);
  auto poses = testing::PerfectPoseStream(gt);
  for (PoseRecord& p : poses) p.process_ms = 25.0;
  const std::string table = Evaluate(gt, poses).Table();
  EXPECT_NE(table.find("100.00 %"), std::string::npos) << table;
  EXPECT_NE(table.find("40.0"), std::string::npos) << table;  // fps
  EXPECT_NE(table.find("position (mm)"), std::string::npos) << table;
}

TEST(Evaluation, BadInputThrows) {
  const auto gt = MakeGroundTruth(5);
  auto poses = testing::PerfectPoseStream(gt);
  auto dup = poses;
  dup.push_back(poses[2]);
  EXPECT_THROW(Evaluate(gt, dup), Error);

  std::vector<GroundTruthFrame> no_gt = {{0, std::nullopt}, {1, std::nullopt}};
  EXPECT_THROW(Evaluate(no_gt, poses), Error);

  auto dup_gt = gt;
  dup_gt.push_back(gt[1]);
  EXPECT_THROW(Evaluate(dup_gt, poses), Error);

  auto nan = poses;
  nan[1].world_from_obj.set_translation(Eigen::Vector3d(NAN, 0, 0));
  EXPECT_THROW(Evaluate(gt, nan), Error);
  // A NaN pose on a lost frame is allowed: it is never scored.
  nan[1].status = TrackStatus::kLost;
  EXPECT_NO_THROW(Evaluate(gt, nan));

  EvaluationOptions bad;
  bad.success_trans_m = 0.0;
  EXPECT_THROW(bad.Check(), Error);
  bad = EvaluationOptions();
  bad.strict_rot_deg = NAN;
  EXPECT_THROW(Evaluate(gt, poses, bad), Error);
  try {
    bad.Check();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("strict_rot_deg"), std::string::npos);
  }
}

TEST(Evaluation, PerFrameCsv) {
  const auto gt = MakeGroundTruth(4);
  auto poses = testing::PerfectPoseStream(gt);
  poses[1].status = TrackStatus::kLost;
  poses.pop_back();
  const EvaluationResult r = Evaluate(gt, poses);
  const std::string path =
      (std::filesystem::temp_directory_path() / "unseen_eval_per_frame_test.csv").string();
  WritePerFrameCsv(path, r);
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[0].substr(0, 19), "frame,status,confid");
  EXPECT_EQ(lines[1].substr(0, 11), "0,tracking,");
  EXPECT_EQ(lines[2].substr(0, 7), "1,lost,");
  EXPECT_EQ(lines[4].substr(0, 10), "3,missing,");
  EXPECT_EQ(lines[2].substr(lines[2].size() - 3), "0,0");
  EXPECT_EQ(lines[1].substr(lines[1].size() - 3), "1,1");
  std::filesystem::remove(path);

  EXPECT_THROW(WritePerFrameCsv("/nonexistent_dir/x.csv", r), Error);
}

}  // namespace
}  // namespace unseen
