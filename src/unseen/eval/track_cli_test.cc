// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// End-to-end tests of `unseen track` on a short synthetic sequence with faults in the middle
// of the stream, running the built binary (UNSEEN_CLI): the command warns, reports those
// frames lost and goes on.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "unseen/eval/cli_testing.h"
#include "unseen/io/pose_stream.h"
#include "unseen/io/sequence.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

std::string TempPath(const std::string& name) {
  return testing::CliTempPath("track_cli_test", name);
}

using testing::ReadText;
using RunResult = testing::CliResult;

RunResult RunCli(const std::string& args) { return testing::RunCli("track_cli_test", args); }

std::string RgbFile(const std::string& dir, int frame) {
  return (fs::path(dir) / "cam0" / "rgb" / fmt::format("{:06d}.png", frame)).string();
}

// The README demo scene's first 12 frames (the cube over clutter), rendered by `unseen synth`.
class TrackCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = TempPath("seq");
    fs::remove_all(dir_);
    const RunResult r = RunCli(
        fmt::format("-q synth '{}/scenes/demo.yaml' '{}' --frames 12", UNSEEN_SOURCE_DIR, dir_));
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string dir_;
};

TEST_F(TrackCli, UnreadableAndMissingFramesAreReportedLostAndTrackingGoesOn) {
  // Frame 4 cut short (an interrupted copy), frame 7 gone.
  fs::resize_file(RgbFile(dir_, 4), fs::file_size(RgbFile(dir_, 4)) / 3);
  fs::remove(RgbFile(dir_, 7));
  const std::string poses = TempPath("poses.csv"), stats = TempPath("stats.json");
  const std::string overlay = TempPath("overlay");
  fs::remove_all(overlay);
  const RunResult r =
      RunCli(fmt::format("track '{}' --init gt --out '{}' --stats '{}' "
                         "--overlay '{}'",
                         dir_, poses, stats, overlay));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // One warning per bad file, naming it.
  EXPECT_NE(r.err.find("000004.png"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("000007.png"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("frame reported lost"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("2 frame(s) with an unreadable image"), std::string::npos) << r.out;

  const std::vector<PoseRecord> records = ReadPoseStream(poses);
  ASSERT_EQ(records.size(), 12u);
  for (const PoseRecord& p : records) {
    EXPECT_TRUE(p.world_from_obj.IsValid()) << "frame " << p.frame;
    EXPECT_TRUE(std::isfinite(p.confidence)) << "frame " << p.frame;
  }
  for (int bad : {4, 7}) {
    EXPECT_EQ(records[bad].frame, bad);
    EXPECT_EQ(records[bad].status, TrackStatus::kLost) << "frame " << bad;
    EXPECT_EQ(records[bad].confidence, 0.0) << "frame " << bad;
  }
  // The held pose is the one of the frame before (tracked; the cube is in plain view).
  EXPECT_EQ(records[3].status, TrackStatus::kTracking);
  EXPECT_LT(Difference(records[4].world_from_obj, records[3].world_from_obj).translation, 1e-9);
  // Tracking went on after each gap.
  EXPECT_EQ(records[5].status, TrackStatus::kTracking);
  EXPECT_EQ(records[8].status, TrackStatus::kTracking);
  EXPECT_EQ(records[11].status, TrackStatus::kTracking);
  const Sequence sequence = Sequence::Open(dir_);
  EXPECT_LT(Difference(records[11].world_from_obj, *sequence.GroundTruth(11)).translation, 0.005);

  const nlohmann::json j = nlohmann::json::parse(ReadText(stats));
  EXPECT_EQ(j["frames"].get<int>(), 12);
  EXPECT_EQ(j["unreadable_frames"].get<int>(), 2);
  EXPECT_GE(j["lost_frames"].get<int>(), 2);
  // The overlay has every frame, the bad ones over black.
  int pngs = 0;
  for (const auto& entry : fs::directory_iterator(overlay))
    pngs += entry.path().extension() == ".png";
  EXPECT_EQ(pngs, 12);
  fs::remove(poses);
  fs::remove(stats);
  fs::remove_all(overlay);
}

// --init auto: the pose of the known model from its box (here the true visible mask's),
// without any pose given; a box where the object is not is an error, not a guess.
TEST_F(TrackCli, InitAutoFindsThePoseFromTheObjectsBox) {
  const cv::Mat mask =
      cv::imread((fs::path(dir_) / "cam0" / "mask_visib" / "000000_000000.png").string(),
                 cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(mask.empty());
  const cv::Rect box = cv::boundingRect(mask);
  const std::string poses = TempPath("auto_poses.csv");
  const RunResult r = RunCli(fmt::format("track '{}' --init auto --roi {},{},{},{} --out '{}'",
                                         dir_, box.x, box.y, box.width, box.height, poses));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("--init auto: frame 0: found"), std::string::npos) << r.err;
  const std::vector<PoseRecord> records = ReadPoseStream(poses);
  ASSERT_EQ(records.size(), 12u);
  const Sequence sequence = Sequence::Open(dir_);
  for (const PoseRecord& p : records) {
    EXPECT_EQ(p.status, TrackStatus::kTracking) << "frame " << p.frame;
    const PoseDifference d = Difference(p.world_from_obj, *sequence.GroundTruth(p.frame));
    EXPECT_LT(d.translation, 0.005) << "frame " << p.frame;
    EXPECT_LT(d.rotation_rad, 0.02) << "frame " << p.frame;
  }
  fs::remove(poses);

  // A box over the background (the cube is elsewhere): no pose, said clearly.
  const int x = box.x > 200 ? 10 : 380;
  const RunResult nowhere =
      RunCli(fmt::format("track '{}' --init auto --roi {},20,100,100", dir_, x));
  EXPECT_NE(nowhere.exit_code, 0);
  EXPECT_NE(nowhere.err.find("no confident pose of the model in --roi"), std::string::npos)
      << nowhere.err;
  // Options that do not go together.
  const RunResult filters_without_auto =
      RunCli(fmt::format("track '{}' --init gt --filters bank.yaml", dir_));
  EXPECT_NE(filters_without_auto.exit_code, 0);
  EXPECT_NE(filters_without_auto.err.find("--filters serves --init auto"), std::string::npos)
      << filters_without_auto.err;
}

TEST_F(TrackCli, SequenceWithoutAnyImageFailsClearly) {
  // Without a first image there is nothing to read the image size from.
  for (int f = 0; f < 12; ++f) fs::remove(RgbFile(dir_, f));
  const RunResult r = RunCli(fmt::format("track '{}' --init gt", dir_));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cam0/rgb"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("000000.png"), std::string::npos) << r.err;
}

// A BOP dataset as it is: dataset/models/obj_<id>.ply beside dataset/test/<scene>/, whose
// scene_gt.json lists several objects per frame. --obj-id picks the one to track and score.
TEST_F(TrackCli, ObjIdPicksTheObjectOfABopSceneOfSeveral) {
  const fs::path dataset = TempPath("bop"), scene = dataset / "test" / "000003";
  fs::remove_all(dataset);
  fs::create_directories(scene);
  fs::create_directories(dataset / "models");
  for (const char* file : {"obj_000001.ply", "obj_000001.png"}) {
    fs::copy_file(fs::path(dir_) / "models" / file, dataset / "models" / file);
  }
  fs::copy(fs::path(dir_) / "cam0" / "rgb", scene / "rgb", fs::copy_options::recursive);
  fs::copy_file(fs::path(dir_) / "cam0" / "scene_camera.json", scene / "scene_camera.json");
  // Object 7 (no model here) comes first in every frame: the default object.
  nlohmann::json gt = nlohmann::json::parse(ReadText((fs::path(dir_) / "cam0" / "scene_gt.json").string()));
  for (auto& [frame, objects] : gt.items()) {
    nlohmann::json other = objects[0];
    other["obj_id"] = 7;
    other["cam_t_m2c"] = {150.0, 80.0, 1400.0};
    objects.insert(objects.begin(), other);
  }
  std::ofstream(scene / "scene_gt.json") << gt.dump(1);

  const std::string poses = TempPath("bop_poses.csv");
  const RunResult chosen = RunCli(
      fmt::format("-q track '{}' --obj-id 1 --init gt --out '{}'", scene.string(), poses));
  ASSERT_EQ(chosen.exit_code, 0) << chosen.err;
  const RunResult scored =
      RunCli(fmt::format("eval '{}' '{}' --obj-id 1 --json", scene.string(), poses));
  ASSERT_EQ(scored.exit_code, 0) << scored.err;
  const nlohmann::json j = nlohmann::json::parse(scored.out);
  EXPECT_EQ(j["success_5cm5deg"].get<double>(), 1.0) << scored.out;
  EXPECT_LT(j["mean_trans_err_mm"].get<double>(), 5.0) << scored.out;
  // Scored against object 7's ground truth instead, the same poses are far off.
  const RunResult other = RunCli(fmt::format("eval '{}' '{}' --json", scene.string(), poses));
  ASSERT_EQ(other.exit_code, 0) << other.err;
  EXPECT_EQ(nlohmann::json::parse(other.out)["success_5cm5deg"].get<double>(), 0.0);

  // The default object has no model: said so, naming the object.
  const RunResult first = RunCli(fmt::format("track '{}' --init gt", scene.string()));
  EXPECT_EQ(first.exit_code, 1);
  EXPECT_NE(first.err.find("obj_000007"), std::string::npos) << first.err;
  // An object the scene does not have is an error listing those it has.
  const RunResult absent = RunCli(fmt::format("track '{}' --obj-id 9 --init gt", scene.string()));
  EXPECT_EQ(absent.exit_code, 1);
  EXPECT_NE(absent.err.find("object 9 is in no frame"), std::string::npos) << absent.err;
  EXPECT_NE(absent.err.find("1, 7"), std::string::npos) << absent.err;
  fs::remove_all(dataset);
  fs::remove(poses);
}

}  // namespace
}  // namespace unseen
