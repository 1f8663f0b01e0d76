// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// End-to-end tests of `unseen run` (the complete system) on a short synthetic sequence,
// running the built binary (UNSEEN_CLI): from a sequence folder, and from a video file
// with its calibration through the path a live camera takes.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "unseen/camera/calibration_io.h"
#include "unseen/eval/cli_testing.h"
#include "unseen/io/pose_stream.h"
#include "unseen/io/sequence.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

std::string TempPath(const std::string& name) { return testing::CliTempPath("run_cli_test", name); }
testing::CliResult RunCli(const std::string& args) { return testing::RunCli("run_cli_test", args); }

// The README demo scene's first 40 frames (the cube over clutter, moving before a still
// camera), rendered by `unseen synth`.
class RunCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = TempPath("seq");
    fs::remove_all(dir_);
    const testing::CliResult r = ::unseen::RunCli(
        fmt::format("-q synth '{}/scenes/demo.yaml' '{}' --frames 40", UNSEEN_SOURCE_DIR, dir_));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    model_ = (fs::path(dir_) / "models" / "obj_000001.ply").string();
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string dir_, model_;
};
std::string RunCli::dir_, RunCli::model_;

// The poses of `records` against the sequence's ground truth: the object is found by frame
// 30 (7 frames learn the background, then each selected region is tried) and every pose
// from then on is the object's, to the end.
void ExpectFoundAndTracked(const std::vector<PoseRecord>& records, const Sequence& sequence) {
  ASSERT_FALSE(records.empty());
  EXPECT_LE(records.front().frame, 30);
  EXPECT_EQ(records.back().frame, sequence.num_frames() - 1);
  for (const PoseRecord& p : records) {
    EXPECT_EQ(p.status, TrackStatus::kTracking) << "frame " << p.frame;
    EXPECT_LT(Difference(p.world_from_obj, *sequence.GroundTruth(p.frame)).translation, 0.01)
        << "frame " << p.frame;
  }
}

TEST_F(RunCli, FindsAndTracksTheKnownModelInASequence) {
  const std::string poses = TempPath("poses.csv");
  const testing::CliResult r =
      ::unseen::RunCli(fmt::format("run '{}' --model '{}' --out '{}'", dir_, model_, poses));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("frames: learning 7"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("lost 0"), std::string::npos) << r.out;
  ExpectFoundAndTracked(ReadPoseStream(poses), Sequence::Open(dir_));
  fs::remove(poses);
}

// The same frames as a video file with a calibration file: the path of a live camera.
TEST_F(RunCli, AVideoFileGoesThroughTheCamerasPath) {
  const Sequence sequence = Sequence::Open(dir_);
  const std::string video = TempPath("frames.avi"), calibration = TempPath("camera.yml");
  const PinholeCamera& camera = sequence.rig().cameras[0].intrinsics;
  {
    cv::VideoWriter writer(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 30.0,
                           cv::Size(camera.width, camera.height));
    ASSERT_TRUE(writer.isOpened());
    for (int i = 0; i < sequence.num_frames(); ++i) {
      writer.write(
          cv::imread((fs::path(dir_) / "cam0" / "rgb" / fmt::format("{:06d}.png", i)).string()));
    }
  }
  SaveOpenCvCalibration(calibration, camera);
  const std::string poses = TempPath("video_poses.csv");
  const testing::CliResult r = ::unseen::RunCli(fmt::format(
      "run '{}' --calibration '{}' --model '{}' --out '{}'", video, calibration, model_, poses));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("40 frames"), std::string::npos) << r.out;
  // No ground truth beside a video: the poses are checked against the sequence's (the
  // frames are numbered alike).
  ExpectFoundAndTracked(ReadPoseStream(poses), sequence);

  // A video without its calibration, and an object without a model on one camera without
  // depth, are clear errors.
  const testing::CliResult no_calibration = ::unseen::RunCli(fmt::format("run '{}'", video));
  EXPECT_NE(no_calibration.exit_code, 0);
  EXPECT_NE(no_calibration.err.find("needs --calibration"), std::string::npos)
      << no_calibration.err;
  const testing::CliResult no_depth = ::unseen::RunCli(fmt::format("run '{}'", dir_));
  EXPECT_NE(no_depth.exit_code, 0);
  EXPECT_NE(no_depth.err.find("has one camera and no depth images"), std::string::npos)
      << no_depth.err;
  EXPECT_NE(no_depth.err.find("--model"), std::string::npos) << no_depth.err;
  fs::remove(video);
  fs::remove(calibration);
  fs::remove(poses);
}

// The whole system's configuration file and the overlay: one drawn frame per input frame,
// the model's outline in green once tracking; a configuration in error names its file.
TEST_F(RunCli, TakesASystemConfigurationAndDrawsTheOverlay) {
  const std::string config = TempPath("system.yaml"), overlay = TempPath("overlay");
  {
    std::ofstream out(config);
    out << "system: {regions: motion, reselect_after_lost_frames: 5}\n"
           "filters: [{type: motion, warmup_frames: 6}]\n"
           "known_pose: {max_candidates: 8}\n";
  }
  fs::remove_all(overlay);
  const testing::CliResult r = ::unseen::RunCli(fmt::format(
      "run '{}' --model '{}' --config '{}' --overlay '{}'", dir_, model_, config, overlay));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("frames: learning 5"), std::string::npos) << r.out;  // warmup 6
  int drawn = 0;
  for (const auto& entry : fs::directory_iterator(overlay))
    drawn += entry.path().extension() == ".png";
  EXPECT_EQ(drawn, 40);
  cv::Mat last = cv::imread((fs::path(overlay) / "frame_000039.png").string());
  ASSERT_FALSE(last.empty());
  cv::Mat green;
  cv::inRange(last, cv::Scalar(0, 200, 0), cv::Scalar(60, 255, 60), green);
  EXPECT_GT(cv::countNonZero(green), 100);

  {
    std::ofstream out(config);
    out << "system: {regions: everywhere}\n";
  }
  const testing::CliResult bad =
      ::unseen::RunCli(fmt::format("run '{}' --model '{}' --config '{}'", dir_, model_, config));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("system.yaml"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("everywhere"), std::string::npos) << bad.err;
  fs::remove_all(overlay);
  fs::remove(config);
}

}  // namespace
}  // namespace unseen
