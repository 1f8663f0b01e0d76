// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/eval/sequence_poses.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "unseen/eval/overlay.h"
#include "unseen/eval/test_sequence.h"
#include "unseen/util/testing.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

std::string TempPath(const std::string& name) {
  return (fs::temp_directory_path() / ("unseen_sequence_poses_test_" + name)).string();
}

TEST(SequencePoses, SyntheticSequenceGroundTruthScoresZero) {
  const auto written = testing::WriteTestSequence(TempPath("seq"), 4);
  const Sequence sequence = Sequence::Open(written.dir);
  const auto gt = SequenceGroundTruth(sequence);
  ASSERT_EQ(gt.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(gt[i].world_from_obj.has_value());
    const PoseDifference d = Difference(*gt[i].world_from_obj, written.world_from_obj[i]);
    EXPECT_LT(d.translation, 1e-6);  // written in millimetres with limited digits
    EXPECT_LT(d.rotation_rad, 1e-6);
  }

  // A CSV stream 5 mm off in world z, read back through ReadPosesForSequence.
  auto records = testing::PerfectPoseStream(gt, 20.0);
  for (PoseRecord& r : records) {
    r.world_from_obj.set_translation(r.world_from_obj.translation() + Eigen::Vector3d(0, 0, 0.005));
  }
  const std::string csv = TempPath("poses.csv");
  WritePoseStream(csv, records);
  const EvaluationResult r = Evaluate(gt, ReadPosesForSequence(csv, sequence));
  EXPECT_NEAR(r.trans_err_mm.mean, 5.0, 1e-6);
  EXPECT_NEAR(r.trans_err_axis_mm[2].max, 5.0, 1e-6);
  EXPECT_NEAR(r.rot_err_deg.max, 0.0, 1e-6);
  ASSERT_TRUE(r.fps.has_value());
  EXPECT_NEAR(*r.fps, 50.0, 1e-9);
  fs::remove(csv);

  // The BOP export of the truth, outside the sequence: placed through the reference camera.
  const std::string bop = TempPath("scene_gt.json");
  ExportBopSceneGt(bop, testing::PerfectPoseStream(gt, 20.0), sequence.rig().cameras[0].cam_from_world(), 1);
  EXPECT_TRUE(IsBopSceneGt(bop));
  const EvaluationResult rb = Evaluate(gt, ReadPosesForSequence(bop, sequence));
  EXPECT_EQ(rb.scored_frames, 4);
  EXPECT_LT(rb.trans_err_mm.max, 1e-3);
  EXPECT_LT(rb.rot_err_deg.max, 1e-4);
  EXPECT_THROW(ReadPosesForSequence(bop, sequence, "cam9"), Error);
  fs::remove(bop);

  // The sequence's own scene_gt.json scores zero.
  const EvaluationResult rs =
      Evaluate(gt, ReadPosesForSequence(written.dir + "/cam0/scene_gt.json", sequence));
  EXPECT_DOUBLE_EQ(rs.success_rate, 1.0);
  EXPECT_LT(rs.trans_err_mm.max, 1e-6);
}

TEST(SequencePoses, JsonLinesWithJsonExtensionIsAStream) {
  const auto written = testing::WriteTestSequence(TempPath("seq_jsonl"), 2);
  const Sequence sequence = Sequence::Open(written.dir);
  const auto gt = SequenceGroundTruth(sequence);
  for (int n : {1, 2}) {  // one line parses as one JSON object too
    auto records = testing::PerfectPoseStream(gt, 20.0);
    records.resize(n);
    const std::string path = TempPath("stream.json");
    WritePoseStream(path, records);
    EXPECT_FALSE(IsBopSceneGt(path));
    const auto back = ReadPosesForSequence(path, sequence);
    ASSERT_EQ(back.size(), size_t(n));
    EXPECT_EQ(back[0].frame, records[0].frame);
    fs::remove(path);
  }
}

TEST(SequencePoses, BadInputThrows) {
  const auto written = testing::WriteTestSequence(TempPath("seq_nogt"), 2, false);
  const Sequence sequence = Sequence::Open(written.dir);
  try {
    SequenceGroundTruth(sequence);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no ground truth"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReadPosesForSequence(TempPath("does_not_exist.csv"), sequence), Error);
  const std::string broken = TempPath("broken.json");
  std::ofstream(broken) << "{\"0\": [{\"obj_id\": 1, \"cam_R_m2c\": [1, 0]}]}";
  EXPECT_THROW(ReadPosesForSequence(broken, sequence), Error);
  std::ofstream(broken) << "{not json";
  EXPECT_THROW(ReadPosesForSequence(broken, sequence), Error);
  fs::remove(broken);
}

TEST(SequencePoses, OverlayOfSyntheticSequenceOutlinesTheObject) {
  const auto written = testing::WriteTestSequence(TempPath("seq_overlay"), 3);
  const Sequence sequence = Sequence::Open(written.dir);
  auto records = testing::PerfectPoseStream(SequenceGroundTruth(sequence), 20.0);
  records[2].status = TrackStatus::kLost;
  const std::string out = TempPath("overlay_frames");
  fs::remove_all(out);
  OverlayOptions options;
  options.line_thickness_px = 1;
  EXPECT_EQ(WriteOverlay(sequence, records, 0, out, 0.0, options), 3);

  const RigCamera& camera = written.rig.cameras[0];
  for (int i = 0; i < 3; ++i) {
    const cv::Mat image = cv::imread(fmt::format("{}/frame_{:06d}.png", out, i));
    ASSERT_FALSE(image.empty()) << i;
    RenderOptions render_options;
    render_options.write_color = false;
    render_options.cull_back_faces = false;
    RenderBuffers buffers;
    Render(written.mesh, camera.intrinsics, camera.cam_from_world() * written.world_from_obj[i],
           camera.intrinsics.ImageRect(), render_options, &buffers);
    const cv::Vec3b expected = i == 2 ? cv::Vec3b(0, 0, 255) : cv::Vec3b(0, 255, 0);
    int outline = 0, blue = 0;
    for (int y = 25; y < image.rows; ++y) {  // below the status line
      for (int x = 0; x < image.cols; ++x) {
        const cv::Vec3b px = image.at<cv::Vec3b>(y, x);
        blue += px == cv::Vec3b(255, 128, 0);
        if (px != expected) continue;
        ++outline;
        EXPECT_TRUE(testing::IsMaskBoundary(buffers.mask, x, y)) << "frame " << i << " at " << x << "," << y;
      }
    }
    EXPECT_GT(outline, 60) << i;
    // The estimate equals the truth: while tracking its outline hides the truth's.
    if (i < 2) {
      EXPECT_EQ(blue, 0) << i;
    }
  }
  fs::remove_all(out);

  EXPECT_THROW(WriteOverlay(sequence, records, 1, out), Error);
  auto dup = records;
  dup.push_back(records[0]);
  EXPECT_THROW(WriteOverlay(sequence, dup, 0, out), Error);
}

TEST(SequencePoses, DevSequenceGroundTruthRoundTripScoresZero) {
  const std::string path = testing::DevSequencesDir() + "cube_white_zigzag";
  if (!fs::exists(path)) GTEST_SKIP() << "no development sequences at " << path;
  const Sequence sequence = Sequence::Open(path);
  const auto gt = SequenceGroundTruth(sequence);
  const std::string stream = TempPath("zigzag.jsonl");
  WritePoseStream(stream, testing::PerfectPoseStream(gt, 20.0));
  const EvaluationResult r = Evaluate(gt, ReadPosesForSequence(stream, sequence));
  fs::remove(stream);
  EXPECT_EQ(r.frames, sequence.num_frames());
  EXPECT_EQ(r.scored_frames, r.frames);
  EXPECT_DOUBLE_EQ(r.success_rate, 1.0);
  EXPECT_DOUBLE_EQ(r.strict_success_rate, 1.0);
  EXPECT_LT(r.trans_err_mm.max, 1e-6);
  EXPECT_LT(r.rot_err_deg.max, 1e-4);
  EXPECT_EQ(r.first_failure_frame, -1);
}

TEST(SequencePoses, DevRigBopFilesArePlacedThroughTheirCamera) {
  const std::string path = testing::DevSequencesDir() + "rig5_cube_fig312";
  if (!fs::exists(path)) GTEST_SKIP() << "no development sequences at " << path;
  const Sequence sequence = Sequence::Open(path);
  const auto gt = SequenceGroundTruth(sequence);
  for (const char* camera : {"cam0", "cam4"}) {
    const std::string file = path + "/" + camera + "/scene_gt.json";
    const EvaluationResult r = Evaluate(gt, ReadPosesForSequence(file, sequence));
    EXPECT_LT(r.trans_err_mm.max, 1e-3) << camera;
    EXPECT_DOUBLE_EQ(r.success_rate, 1.0) << camera;
  }
  // cam0's poses read as if they were the reference camera's: off by the 100 mm baseline.
  const EvaluationResult wrong =
      Evaluate(gt, ReadPosesForSequence(path + "/cam0/scene_gt.json", sequence, "cam2"));
  EXPECT_NEAR(wrong.trans_err_mm.mean, 100.0, 0.5);
}

}  // namespace
}  // namespace unseen
