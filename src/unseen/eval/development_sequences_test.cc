// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// End-to-end accuracy on the development sequences that are not the tracker's own renders
// (../shared/data/sequences, skipped when absent): `unseen track SEQ --init gt` with the
// default options, or with a modality switched off, then `unseen eval SEQ POSES --json`.
// The thresholds sit below what the tracker measures (README "Real footage, untextured
// and held-out objects") so that a regression in the general case fails here.
//
// UNSEEN_TEST_FRAMES=N (scripts/sanitize.sh) tracks each sequence over its first N frames
// only and scores those: under the sanitizers tracking is ~10x slower, and the first 40
// frames take the code paths the whole sequence does (a model build and its first update
// at frame 30).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "unseen/eval/cli_testing.h"
#include "unseen/io/pose_stream.h"
#include "unseen/track/tracker_options.h"
#include "unseen/util/testing.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

struct Expectation {
  std::string name;  // of the test case
  std::string sequence;
  std::string config_yaml;  // tracker options; empty: the defaults
  double min_success;       // at 5 cm / 5 deg
  int max_lost;
  std::string track_args = "";  // more arguments of `unseen track`
  double max_mean_mm = 1e9;     // mean position error
};

// The frames each sequence is tracked over: UNSEEN_TEST_FRAMES, or 0 for all of them.
int FramesToTrack() {
  const char* frames = std::getenv("UNSEEN_TEST_FRAMES");
  return frames == nullptr ? 0 : std::max(0, std::atoi(frames));
}

// The share of the tracked frames (those in the pose stream) that succeed at 5 cm / 5 deg.
double SuccessOfTrackedFrames(const nlohmann::json& score) {
  const int frames = score.at("frames").get<int>();
  const int tracked = frames - score.at("missing_frames").get<int>();
  return tracked > 0 ? score.at("success_5cm5deg").get<double>() * frames / tracked : 0.0;
}

// Tracks `e.sequence` from its first true pose (over FramesToTrack()) and returns `unseen
// eval --json`'s object; the test is skipped when the sequence is absent.
nlohmann::json TrackAndScore(const Expectation& e, const std::string& tag) {
  const std::string seq = testing::DevSequencesDir() + e.sequence;
  if (!fs::is_directory(seq)) return nullptr;
  const std::string prefix = "development_sequences_test";
  const std::string poses = testing::CliTempPath(prefix, tag + "_poses.csv");
  std::string config_arg;
  if (!e.config_yaml.empty()) {
    const std::string config = testing::CliTempPath(prefix, tag + "_options.yaml");
    std::ofstream(config) << e.config_yaml;
    config_arg = fmt::format(" --config '{}'", config);
  }
  const std::string frames_arg =
      FramesToTrack() > 0 ? fmt::format(" --max-frames {}", FramesToTrack()) : "";
  const testing::CliResult track =
      testing::RunCli(prefix, fmt::format("-q track '{}' --init gt{}{} {} --out '{}'", seq,
                                          config_arg, frames_arg, e.track_args, poses));
  EXPECT_EQ(track.exit_code, 0) << track.err;
  const testing::CliResult eval =
      testing::RunCli(prefix, fmt::format("eval '{}' '{}' --json", seq, poses));
  EXPECT_EQ(eval.exit_code, 0) << eval.err;
  return nlohmann::json::parse(eval.out);
}

class DevelopmentSequence : public ::testing::TestWithParam<Expectation> {};

TEST_P(DevelopmentSequence, TrackedFromTheTruePose) {
  const Expectation& e = GetParam();
  const nlohmann::json score = TrackAndScore(e, e.name);
  if (score.is_null()) GTEST_SKIP() << e.sequence << " not found in " << testing::DevSequencesDir();
  EXPECT_GE(SuccessOfTrackedFrames(score), e.min_success) << score.dump();
  EXPECT_LE(score.at("lost_frames").get<int>(), e.max_lost) << score.dump();
  EXPECT_LE(score.at("mean_trans_err_mm").get<double>(), e.max_mean_mm) << score.dump();
}

INSTANTIATE_TEST_SUITE_P(
    RealAndUntextured, DevelopmentSequence,
    ::testing::Values(
        // Real RealSense footage (motion blur, auto exposure): colour and depth.
        Expectation{"RealCube", "visp_rbt_cube", "", 0.98, 0},
        // The same without its depth images: texture and silhouette through the blurred
        // stretch, where a residual bound made for renders once declared it lost.
        Expectation{"RealCubeColourOnly", "visp_rbt_cube", "depth: {enabled: false}\n", 0.95, 2},
        // An untextured glossy figure: the silhouette alone.
        Expectation{"UntexturedGlossyFigure", "wuson_handheld_pointlight", "", 0.98, 0},
        // Without their models (SPEC 5), built in the true object frame and a build fused
        // into it every 30 frames (within the frame, for a reproducible run): the real cube
        // from the sensor's depth (measured 100 %, 11.5 mm; the exact model 11.3 mm), the
        // 5-camera cube by the plane sweep (measured 100 %, 0.8 mm; the exact model
        // 0.8 mm). The thesis's periodic rebuild (measured 100 %, 1.4 mm in the portable
        // build, 96.7 %, 1.4 mm built for a CPU with AVX-512: its rebuilds inherit the
        // tracked pose's error, and the rotation drifts past 5 deg in the last frames).
        Expectation{"RealCubeWithoutItsModel", "visp_rbt_cube", "", 0.98, 0,
                    "--unknown --depth sensor --update-in-frame", 14.0},
        Expectation{"FiveCameraCubeWithoutItsModel", "rig5_cube_fig312", "", 0.95, 0,
                    "--unknown --depth planesweep --update-in-frame", 2.0},
        Expectation{"FiveCameraCubeRebuiltPeriodically", "rig5_cube_fig312", "", 0.9, 0,
                    "--unknown --depth planesweep --update periodic --update-in-frame", 3.0}),
    [](const ::testing::TestParamInfo<Expectation>& info) { return info.param.name; });

// Every `stride`-th frame of the one-camera sequence `source` as a sequence of its own in
// `out` (renumbered from 0, at fps / stride; images and model linked, not copied): the
// same footage filmed by a faster hand.
void WriteStridedSequence(const fs::path& source, const fs::path& out, int stride) {
  auto read = [](const fs::path& path) { return nlohmann::json::parse(std::ifstream(path)); };
  fs::remove_all(out);
  fs::create_directories(out / "cam0");
  nlohmann::json sequence = read(source / "sequence.json");
  ASSERT_EQ(sequence.at("cameras").size(), 1u) << source;
  const fs::path cam = source / sequence.at("cameras")[0].get<std::string>();
  const nlohmann::json cameras = read(cam / "scene_camera.json");
  const nlohmann::json truth = read(cam / "scene_gt.json");
  nlohmann::json kept_cameras, kept_truth;
  for (int from = 0, to = 0; cameras.contains(std::to_string(from)); from += stride, ++to) {
    kept_cameras[std::to_string(to)] = cameras.at(std::to_string(from));
    kept_truth[std::to_string(to)] = truth.at(std::to_string(from));
    for (const char* folder : {"rgb", "depth"}) {
      const fs::path image = cam / folder / fmt::format("{:06d}.png", from);
      if (!fs::exists(image)) continue;
      fs::create_directories(out / "cam0" / folder);
      fs::create_symlink(fs::absolute(image),
                         out / "cam0" / folder / fmt::format("{:06d}.png", to));
    }
  }
  std::ofstream(out / "cam0" / "scene_camera.json") << kept_cameras.dump();
  std::ofstream(out / "cam0" / "scene_gt.json") << kept_truth.dump();
  sequence["cameras"] = {"cam0"};
  sequence["reference_camera"] = "cam0";
  sequence["fps"] = sequence.value("fps", 30.0) / stride;
  std::ofstream(out / "sequence.json") << sequence.dump();
  fs::create_directory_symlink(fs::absolute(source / "models"), out / "models");
}

// The real RGB-D cube at 15 fps (every second frame): twice the motion between frames, and
// its motion-blurred stretch begins in frames 21-23, where texture and contour fit far worse
// than on the sharp frames their references were learnt from while the measured depth
// agrees (FailureOptions::depth_vouch_agreement): every frame up to there stays tracked
// above the lost confidence (frame 23 at 0.00 without the depth's word). The whole run is
// chaotic after the blur (measured 96 %, 2 lost in the portable build, 84 %, 7 lost built
// for AVX-512; 82 %, 9 lost without the depth's word): its first 24 frames are tested.
TEST(DevelopmentSequenceFaults, RealCubeFilmedTwiceAsFastIsTrackedIntoItsBlur) {
  const fs::path source = fs::path(testing::DevSequencesDir()) / "visp_rbt_cube";
  if (!fs::is_directory(source)) GTEST_SKIP() << source << " not found";
  const std::string prefix = "development_sequences_test";
  const fs::path strided = testing::CliTempPath(prefix, "visp_stride2");
  WriteStridedSequence(source, strided, 2);
  const std::string poses = testing::CliTempPath(prefix, "stride2_poses.csv");
  const testing::CliResult track = testing::RunCli(
      prefix,
      fmt::format("-q track '{}' --init gt --max-frames 24 --out '{}'", strided.string(), poses));
  ASSERT_EQ(track.exit_code, 0) << track.err;
  const std::vector<PoseRecord> records = ReadPoseStream(poses);
  ASSERT_EQ(records.size(), 24u);
  const double lost_confidence = TrackerOptions().failure.lost_confidence;
  for (const PoseRecord& record : records) {
    EXPECT_EQ(record.status, TrackStatus::kTracking) << "frame " << record.frame;
    EXPECT_GE(record.confidence, lost_confidence) << "frame " << record.frame;
  }
  const testing::CliResult eval =
      testing::RunCli(prefix, fmt::format("eval '{}' '{}' --json", strided.string(), poses));
  ASSERT_EQ(eval.exit_code, 0) << eval.err;
  const nlohmann::json score = nlohmann::json::parse(eval.out);
  EXPECT_NEAR(SuccessOfTrackedFrames(score), 1.0, 1e-9) << score.dump();
  fs::remove_all(strided);
}

// The untextured figure with 35 of its frames blacked out (40-74): meanwhile it turns by
// ~60 degrees and moves. Lost through the blackout, it must be found again when it shows:
// the search scores its candidates by the silhouette with the colour statistics learnt
// before the loss (without them no candidate scored, and 40 frames were all it kept).
TEST(DevelopmentSequenceFaults, UntexturedFigureIsFoundAgainAfterABlackout) {
  const fs::path source = fs::path(testing::DevSequencesDir()) / "wuson_handheld_pointlight";
  if (!fs::is_directory(source)) GTEST_SKIP() << source << " not found";
  // The blackout and the search after it need the first 100 frames (the search itself is
  // tested on renders in track/reacquisition_test).
  if (FramesToTrack() > 0 && FramesToTrack() < 100) {
    GTEST_SKIP() << "UNSEEN_TEST_FRAMES=" << FramesToTrack() << ": fewer than its 100 frames";
  }
  const fs::path copy = testing::CliTempPath("development_sequences_test", "blackout");
  fs::remove_all(copy);
  fs::copy(source, copy, fs::copy_options::recursive);
  std::vector<fs::path> frames;
  for (const auto& entry : fs::directory_iterator(copy / "cam0" / "rgb")) {
    frames.push_back(entry.path());
  }
  std::sort(frames.begin(), frames.end());
  ASSERT_GE(frames.size(), 100u);
  for (size_t k = 40; k < 75; ++k) {
    cv::Mat image = cv::imread(frames[k].string());
    ASSERT_FALSE(image.empty()) << frames[k];
    image.setTo(0);
    ASSERT_TRUE(cv::imwrite(frames[k].string(), image));
  }
  const std::string prefix = "development_sequences_test";
  const std::string poses = testing::CliTempPath(prefix, "blackout_poses.csv");
  const testing::CliResult track = testing::RunCli(
      prefix, fmt::format("-q track '{}' --init gt --out '{}'", copy.string(), poses));
  ASSERT_EQ(track.exit_code, 0) << track.err;
  const testing::CliResult eval =
      testing::RunCli(prefix, fmt::format("eval '{}' '{}' --json", copy.string(), poses));
  ASSERT_EQ(eval.exit_code, 0) << eval.err;
  const nlohmann::json score = nlohmann::json::parse(eval.out);
  // Measured: 77 % (the 35 dark frames and a few after them are the rest).
  EXPECT_GE(score.at("success_5cm5deg").get<double>(), 0.7) << score.dump();
  fs::remove_all(copy);
}

}  // namespace
}  // namespace unseen
