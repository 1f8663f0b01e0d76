// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// End-to-end tests of `unseen eval` and `unseen overlay`, running the built binary
// (UNSEEN_CLI) on a tiny synthetic sequence.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "unseen/eval/sequence_poses.h"
#include "unseen/eval/test_sequence.h"
#include "unseen/eval/cli_testing.h"
#include "unseen/io/pose_stream.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

std::string TempPath(const std::string& name) {
  return testing::CliTempPath("eval_cli_test", name);
}

using testing::ReadText;
using RunResult = testing::CliResult;

RunResult RunCli(const std::string& args) { return testing::RunCli("eval_cli_test", args); }

class EvalCli : public ::testing::Test {
 protected:
  void SetUp() override {
    seq_ = testing::WriteTestSequence(TempPath("seq"), 5);
    // Estimates 10 mm off in world x; frame 3 lost; frame 4 missing; 40 ms per frame.
    std::vector<PoseRecord> records;
    for (int i = 0; i < 4; ++i) {
      PoseRecord r;
      r.frame = i;
      r.time_s = i / 25.0;
      r.status = i == 3 ? TrackStatus::kLost : TrackStatus::kTracking;
      r.confidence = i == 3 ? 0.1 : 0.9;
      r.world_from_obj = seq_.world_from_obj[i];
      r.world_from_obj.set_translation(r.world_from_obj.translation() +
                                       Eigen::Vector3d(0.010, 0, 0));
      r.process_ms = 40.0;
      records.push_back(r);
    }
    poses_ = TempPath("poses.csv");
    WritePoseStream(poses_, records);
  }
  void TearDown() override {
    fs::remove_all(seq_.dir);
    fs::remove(poses_);
  }

  testing::TestSequence seq_;
  std::string poses_;
};

TEST_F(EvalCli, JsonOutputHasTheKnownErrors) {
  const RunResult r = RunCli(fmt::format("eval '{}' '{}' --json", seq_.dir, poses_));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["frames"].get<int>(), 5);
  EXPECT_EQ(j["lost_frames"].get<int>(), 1);
  EXPECT_EQ(j["missing_frames"].get<int>(), 1);
  EXPECT_DOUBLE_EQ(j["success_5cm5deg"].get<double>(), 0.6);
  EXPECT_DOUBLE_EQ(j["success_2cm2deg"].get<double>(), 0.6);
  EXPECT_NEAR(j["mean_trans_err_mm"].get<double>(), 10.0, 1e-3);
  EXPECT_NEAR(j["rms_trans_err_mm"].get<double>(), 10.0, 1e-3);
  EXPECT_NEAR(j["max_trans_err_mm"].get<double>(), 10.0, 1e-3);
  EXPECT_NEAR(j["mean_trans_err_mm_xyz"][0].get<double>(), 10.0, 1e-3);
  EXPECT_NEAR(j["mean_trans_err_mm_xyz"][1].get<double>(), 0.0, 1e-3);
  EXPECT_NEAR(j["mean_rot_err_deg"].get<double>(), 0.0, 1e-3);
  EXPECT_NEAR(j["max_rot_err_deg"].get<double>(), 0.0, 1e-3);
  EXPECT_EQ(j["first_failure_frame"].get<int>(), 3);
  EXPECT_NEAR(j["fps"].get<double>(), 25.0, 1e-9);
}

TEST_F(EvalCli, GroundTruthAuditScoresTheTrustedFramesOnly) {
  // Frames 3 and 4 have ground truth 3 cm behind the surface their depth shows.
  const std::string dir = testing::WriteRgbdTestSequence(TempPath("rgbd"), 5, 3);
  const std::string poses = TempPath("rgbd_poses.csv");
  WritePoseStream(poses, testing::PerfectPoseStream(SequenceGroundTruth(Sequence::Open(dir))));
  const RunResult audited = RunCli(fmt::format("eval '{}' '{}' --json --audit-gt", dir, poses));
  ASSERT_EQ(audited.exit_code, 0) << audited.err;
  const nlohmann::json a = nlohmann::json::parse(audited.out);
  EXPECT_EQ(a["frames"].get<int>(), 5);
  EXPECT_EQ(a["ground_truth_audit"]["trusted"].get<int>(), 3);
  EXPECT_EQ(a["ground_truth_audit"]["depth_agreement"].size(), 5u);
  const RunResult trusted = RunCli(fmt::format("eval '{}' '{}' --trusted-gt", dir, poses));
  ASSERT_EQ(trusted.exit_code, 0) << trusted.err;
  EXPECT_NE(trusted.out.find("3 trusted"), std::string::npos) << trusted.out;
  EXPECT_NE(trusted.out.find("frames with ground truth         3"), std::string::npos)
      << trusted.out;
  const RunResult plain = RunCli(fmt::format("eval '{}' '{}' --json", dir, poses));
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_FALSE(nlohmann::json::parse(plain.out).contains("ground_truth_audit"));
  // A sequence without depth cannot be audited.
  const RunResult no_depth = RunCli(fmt::format("eval '{}' '{}' --audit-gt", seq_.dir, poses_));
  EXPECT_NE(no_depth.exit_code, 0);
  EXPECT_NE(no_depth.err.find("no depth"), std::string::npos) << no_depth.err;
  fs::remove_all(dir);
  fs::remove(poses);
}

TEST_F(EvalCli, TableAndPerFrameCsv) {
  const std::string csv = TempPath("per_frame.csv");
  const RunResult r = RunCli(fmt::format("eval '{}' '{}' --per-frame '{}'", seq_.dir, poses_, csv));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("60.00 %"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("position (mm)"), std::string::npos) << r.out;
  const std::string text = ReadText(csv);
  EXPECT_NE(text.find("\n3,lost,"), std::string::npos) << text;
  EXPECT_NE(text.find("\n4,missing,"), std::string::npos) << text;
  fs::remove(csv);
}

TEST_F(EvalCli, AlignFirstRemovesTheOffset) {
  const RunResult r = RunCli(fmt::format("eval '{}' '{}' --json --align-first", seq_.dir, poses_));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  // A world-x offset d is not a fixed object-frame offset while the object turns: after
  // aligning at frame 0 the error of frame i is |d - R_i R_0^T d|, zero at frame 0.
  EXPECT_TRUE(j["align_first"].get<bool>());
  EXPECT_FALSE(j["alignment_offset"].is_null());
  const Eigen::Vector3d d(0.010, 0, 0);
  const Eigen::Matrix3d r0 = seq_.world_from_obj[0].RotationMatrix();
  double max_mm = 0.0;
  for (int i = 0; i < 3; ++i) {  // frames 0..2 are tracked
    const Eigen::Matrix3d ri = seq_.world_from_obj[i].RotationMatrix();
    max_mm = std::max(max_mm, (d - ri * r0.transpose() * d).norm() * 1000.0);
  }
  EXPECT_GT(max_mm, 0.1);
  EXPECT_NEAR(j["max_trans_err_mm"].get<double>(), max_mm, 1e-3);
  EXPECT_NEAR(j["max_rot_err_deg"].get<double>(), 0.0, 1e-3);
}

TEST_F(EvalCli, BadInputFailsWithAClearMessage) {
  RunResult r = RunCli(fmt::format("eval '{}' '{}'", seq_.dir, TempPath("missing.csv")));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("missing.csv"), std::string::npos) << r.err;

  r = RunCli(fmt::format("eval '{}' '{}'", TempPath("no_such_sequence"), poses_));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no_such_sequence"), std::string::npos) << r.err;

  const auto no_gt = testing::WriteTestSequence(TempPath("seq_no_gt"), 2, false);
  r = RunCli(fmt::format("eval '{}' '{}'", no_gt.dir, poses_));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no ground truth"), std::string::npos) << r.err;
  fs::remove_all(no_gt.dir);

  const std::string bad = TempPath("bad.csv");
  std::ofstream(bad) << "frame,time_s,status\n0,0,flying\n";
  r = RunCli(fmt::format("eval '{}' '{}'", seq_.dir, bad));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("bad.csv"), std::string::npos) << r.err;
  fs::remove(bad);
}

TEST_F(EvalCli, OverlayWritesVideoAndFrames) {
  const std::string video = TempPath("overlay.avi");
  fs::remove(video);
  RunResult r = RunCli(fmt::format("-q overlay '{}' '{}' '{}'", seq_.dir, poses_, video));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GT(fs::file_size(video), 0u);
  fs::remove(video);

  const std::string folder = TempPath("overlay_frames");
  fs::remove_all(folder);
  r = RunCli(
      fmt::format("-q overlay '{}' '{}' '{}' --camera cam0 --fps 10", seq_.dir, poses_, folder));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int pngs = 0;
  for (const auto& entry : fs::directory_iterator(folder))
    pngs += entry.path().extension() == ".png";
  EXPECT_EQ(pngs, 5);
  fs::remove_all(folder);

  r = RunCli(fmt::format("-q overlay '{}' '{}' '{}'", seq_.dir, poses_, TempPath("out.xyz")));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("out.xyz"), std::string::npos) << r.err;
  r = RunCli(fmt::format("-q overlay '{}' '{}' '{}' --camera cam7", seq_.dir, poses_, folder));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cam7"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace unseen
