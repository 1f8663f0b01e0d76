// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/io/sequence.h"

#include <filesystem>
#include <fstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "unseen/util/error.h"
#include "unseen/util/testing.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using ::testing::HasSubstr;

const std::string kSequences = std::string(UNSEEN_SOURCE_DIR) + "/../shared/data/sequences/";

fs::path TestDir() { return testing::TestDir("sequence"); }

using testing::ExpectError;

void WriteJson(const fs::path& path, const json& j) {
  std::ofstream out(path);
  out << j.dump(1);
}

// A deterministic test image: a gradient plus a per-frame square.
cv::Mat TestImage(int width, int height, int frame, int camera) {
  cv::Mat image(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<uint8_t>(x * 4 + camera * 20), static_cast<uint8_t>(y * 5),
                    static_cast<uint8_t>(frame * 30));
    }
  }
  cv::rectangle(image, cv::Rect(2 + frame, 3, 5, 5), cv::Scalar(255, 255, 255), cv::FILLED);
  return image;
}

// The JSON of a valid small multi-camera sequence, editable before it is written.
struct TestSequence {
  int width = 40, height = 30, cameras = 2, frames = 3;
  json sequence;
  std::vector<json> scene_camera, scene_gt;

  TestSequence() {
    sequence = {{"fps", 10},
                {"cameras", json::array()},
                {"reference_camera", "cam1"},
                {"object", {{"obj_id", 3}}}};
    for (int c = 0; c < cameras; ++c) {
      sequence["cameras"].push_back("cam" + std::to_string(c));
      json cam = json::object(), gt = json::object();
      for (int f = 0; f < frames; ++f) {
        cam[std::to_string(f)] = {{"cam_K", {50.0, 0, 19.5, 0, 50.0, 14.5, 0, 0, 1}},
                                  {"depth_scale", 1.0},
                                  {"cam_R_w2c", {1, 0, 0, 0, 1, 0, 0, 0, 1}},
                                  {"cam_t_w2c", {-100.0 * c, 0, 0}}};
        // The object at world (10 f, 0, 500) mm: model->camera adds the camera offset.
        gt[std::to_string(f)] = json::array(
            {{{"obj_id", 5}, {"cam_R_m2c", {1, 0, 0, 0, 1, 0, 0, 0, 1}}, {"cam_t_m2c", {0, 0, 1}}},
             {{"obj_id", 3},
              {"cam_R_m2c", {1, 0, 0, 0, 1, 0, 0, 0, 1}},
              {"cam_t_m2c", {10.0 * f - 100.0 * c, 0, 500}}}});
      }
      scene_camera.push_back(cam);
      scene_gt.push_back(gt);
    }
  }

  void Write(const fs::path& dir) const {
    WriteJson(dir / "sequence.json", sequence);
    for (int c = 0; c < cameras; ++c) {
      const fs::path cam_dir = dir / ("cam" + std::to_string(c));
      fs::create_directories(cam_dir / "rgb");
      WriteJson(cam_dir / "scene_camera.json", scene_camera[c]);
      WriteJson(cam_dir / "scene_gt.json", scene_gt[c]);
      for (int f = 0; f < frames; ++f) {
        char name[32];
        std::snprintf(name, sizeof(name), "%06d.png", f);
        cv::imwrite((cam_dir / "rgb" / name).string(), TestImage(width, height, f, c));
      }
    }
  }
};

// --- Development sequences ------------------------------------------------------------

TEST(SequenceDevData, OpensEverySequence) {
  if (!fs::is_directory(kSequences)) GTEST_SKIP() << "no development sequences";
  const std::map<std::string, std::pair<int, int>> expected = {{"box_occluded_bar", {282, 1}},
                                                               {"cube_clutter_sidelight", {282, 1}},
                                                               {"cube_white_zigzag", {282, 1}},
                                                               {"rig5_cube_fig312", {240, 5}},
                                                               {"sphere_clutter_spin", {240, 1}}};
  for (const auto& [name, counts] : expected) {
    SCOPED_TRACE(name);
    if (!fs::is_directory(kSequences + name)) continue;
    const Sequence seq = Sequence::Open(kSequences + name);
    EXPECT_EQ(seq.num_frames(), counts.first);
    EXPECT_EQ(seq.rig().size(), counts.second);
    EXPECT_DOUBLE_EQ(seq.fps(), 30.0);
    EXPECT_TRUE(seq.has_ground_truth());
    EXPECT_FALSE(seq.has_depth());
    EXPECT_EQ(seq.obj_id(), 1);
    EXPECT_THAT(seq.model_path(), HasSubstr("obj_000001.obj"));
    EXPECT_TRUE(fs::is_regular_file(seq.model_path()));
    for (const RigCamera& camera : seq.rig().cameras) {
      EXPECT_EQ(camera.intrinsics.width, 512);
      EXPECT_EQ(camera.intrinsics.height, 256);
      EXPECT_DOUBLE_EQ(camera.intrinsics.fx, 837.3);
      EXPECT_DOUBLE_EQ(camera.intrinsics.cx, 255.5);
    }
    const Frame frame = seq.ReadFrame(seq.num_frames() - 1);
    EXPECT_EQ(frame.frame_id, seq.num_frames() - 1);
    EXPECT_NEAR(frame.time_s, (seq.num_frames() - 1) / 30.0, 1e-12);
    ASSERT_EQ(static_cast<int>(frame.images.size()), counts.second);
    EXPECT_TRUE(frame.depths.empty());
    for (const cv::Mat& image : frame.images) {
      EXPECT_EQ(image.type(), CV_32FC3);
      EXPECT_EQ(image.cols, 512);
      EXPECT_EQ(image.rows, 256);
      double lo = 0, hi = 0;
      cv::minMaxLoc(image.reshape(1), &lo, &hi);
      EXPECT_GE(lo, 0.0);
      EXPECT_LE(hi, 1.0);
      EXPECT_GT(hi, lo);  // not blank
    }
  }
}

TEST(SequenceDevData, CubeStartsOneMetreAway) {
  const std::string path = kSequences + "cube_white_zigzag";
  if (!fs::is_directory(path)) GTEST_SKIP() << "no development sequences";
  const Sequence seq = Sequence::Open(path);
  const std::optional<Rigid3d> gt = seq.GroundTruth(0);
  ASSERT_TRUE(gt.has_value());
  EXPECT_TRUE(gt->translation().isApprox(Eigen::Vector3d(0, 0, 1.0), 1e-9));
  EXPECT_EQ(seq.rig().cameras[0].name, "cam0");
  EXPECT_TRUE(seq.rig().cameras[0].world_from_cam.translation().isZero());
  // The 96 mm cube model, loaded in metres.
  const Mesh model = seq.LoadModel();
  Eigen::Vector3f min, max;
  model.BoundingBox(&min, &max);
  EXPECT_TRUE((max - min).isApprox(Eigen::Vector3f::Constant(0.096f), 1e-4f));
  EXPECT_GT(model.num_triangles(), 0);
}

TEST(SequenceDevData, Rig5ExtrinsicsAndGroundTruthAgree) {
  const std::string path = kSequences + "rig5_cube_fig312";
  if (!fs::is_directory(path)) GTEST_SKIP() << "no development sequences";
  Sequence seq = Sequence::Open(path);
  ASSERT_EQ(seq.rig().size(), 5);
  EXPECT_EQ(seq.reference_camera(), 2);
  for (int c = 0; c < 5; ++c) {
    const Rigid3d& world_from_cam = seq.rig().cameras[c].world_from_cam;
    EXPECT_TRUE(
        world_from_cam.translation().isApprox(Eigen::Vector3d(-0.1 + 0.05 * c, 0, 0), 1e-12))
        << world_from_cam.ToString();
    EXPECT_LT(world_from_cam.rotation().angularDistance(Eigen::Quaterniond::Identity()), 1e-12);
  }
  EXPECT_TRUE(seq.rig().cameras[2].world_from_cam.translation().isZero());
  for (int i = 0; i < seq.num_frames(); ++i) {
    const std::optional<Rigid3d> reference = seq.GroundTruth(i);
    ASSERT_TRUE(reference.has_value());
    for (int c = 0; c < 5; ++c) {
      const std::optional<Rigid3d> own = seq.GroundTruthFromCamera(i, c);
      ASSERT_TRUE(own.has_value());
      const PoseDifference d = Difference(*own, *reference);
      EXPECT_LT(d.translation, 1e-6) << "frame " << i << " camera " << c;
      EXPECT_LT(d.rotation_rad, 1e-6) << "frame " << i << " camera " << c;
    }
  }
  // The Fig. 3.12 path starts at (-120, 0, 1000) mm in the world (= cam2).
  EXPECT_TRUE(seq.GroundTruth(0)->translation().isApprox(Eigen::Vector3d(-0.12, 0, 1.0), 1e-9));

  seq.SelectCameras({"cam4", "cam0"});
  ASSERT_EQ(seq.rig().size(), 2);
  EXPECT_EQ(seq.rig().cameras[0].name, "cam4");
  EXPECT_EQ(seq.reference_camera(), 0);  // cam2 not selected: the first one
  const Frame frame = seq.ReadFrame(10);
  EXPECT_EQ(frame.images.size(), 2u);
  const PoseDifference d = Difference(*seq.GroundTruth(10), *seq.GroundTruthFromCamera(10, 1));
  EXPECT_LT(d.translation, 1e-6);
  ExpectError([&] { seq.SelectCameras({"cam9"}); }, {"cam9", "unknown camera"});
}

TEST(SequenceDevData, PlainBopSceneFolder) {
  const std::string path = kSequences + "cube_white_zigzag/cam0";
  if (!fs::is_directory(path)) GTEST_SKIP() << "no development sequences";
  const Sequence seq = Sequence::Open(path);
  EXPECT_EQ(seq.num_frames(), 282);
  ASSERT_EQ(seq.rig().size(), 1);
  EXPECT_EQ(seq.rig().cameras[0].name, "cam0");
  EXPECT_EQ(seq.obj_id(), 1);  // the first object in scene_gt.json
  EXPECT_DOUBLE_EQ(seq.fps(), 30.0);
  EXPECT_TRUE(seq.GroundTruth(0)->translation().isApprox(Eigen::Vector3d(0, 0, 1.0), 1e-9));
  // models/ is one level up, as in a BOP dataset.
  EXPECT_THAT(seq.model_path(), HasSubstr("cube_white_zigzag/models/obj_000001.obj"));
}

// --- Synthetic sequences --------------------------------------------------------------

TEST(Sequence, ReadsSmallMultiCameraSequence) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.Write(dir);
  const Sequence seq = Sequence::Open(dir.string());
  EXPECT_EQ(seq.num_frames(), 3);
  EXPECT_EQ(seq.rig().size(), 2);
  EXPECT_EQ(seq.reference_camera(), 1);
  EXPECT_DOUBLE_EQ(seq.fps(), 10.0);
  EXPECT_EQ(seq.obj_id(), 3);
  EXPECT_TRUE(seq.model_path().empty());
  ExpectError([&] { seq.LoadModel(); }, {"no object model"});
  for (int i = 0; i < 3; ++i) {
    for (int c = 0; c < 2; ++c) {
      const Rigid3d gt = *seq.GroundTruthFromCamera(i, c);
      EXPECT_TRUE(gt.translation().isApprox(Eigen::Vector3d(0.01 * i, 0, 0.5), 1e-12));
    }
  }
  const Frame frame = seq.ReadFrame(2);
  EXPECT_EQ(frame.frame_id, 2);
  EXPECT_DOUBLE_EQ(frame.time_s, 0.2);
  const cv::Mat expected = TestImage(40, 30, 2, 1);
  cv::Mat expected_float;
  expected.convertTo(expected_float, CV_32FC3, 1.0 / 255.0);
  EXPECT_EQ(cv::norm(frame.images[1], expected_float, cv::NORM_INF), 0.0);
  ExpectError([&] { seq.ReadFrame(3); }, {"frame index 3"});
}

TEST(Sequence, OpensTheObjectAskedForInASceneOfSeveral) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.Write(dir);
  const Sequence five = Sequence::Open(dir.string(), 5);
  EXPECT_EQ(five.obj_id(), 5);
  EXPECT_TRUE(five.GroundTruthFromCamera(0, 0)->translation().isApprox(
      Eigen::Vector3d(0, 0, 0.001), 1e-12));
  EXPECT_EQ(Sequence::Open(dir.string(), 3).obj_id(), 3);  // sequence.json's own
  ExpectError([&] { Sequence::Open(dir.string(), 4); },
              {"object 4 is in no frame", "objects there: 3, 5"});
  ExpectError([&] { Sequence::Open(dir.string(), -1); }, {"object id -1"});
}

TEST(Sequence, UndistortsWithTheSameIntrinsics) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.cameras = 1;
  t.sequence["cameras"] = {"cam0"};
  t.sequence["reference_camera"] = "cam0";
  const std::vector<double> dist = {-0.3, 0.1, 0.001, -0.002, 0.0};
  for (auto& [key, entry] : t.scene_camera[0].items()) entry["dist"] = dist;
  t.Write(dir);
  const Sequence seq = Sequence::Open(dir.string());
  EXPECT_TRUE(seq.rig().cameras[0].intrinsics.distortion.empty());  // frames are undistorted
  EXPECT_DOUBLE_EQ(seq.rig().cameras[0].intrinsics.fx, 50.0);
  const Frame frame = seq.ReadFrame(1);
  // Compare with OpenCV's own undistortion of the same image.
  cv::Mat raw;
  TestImage(40, 30, 1, 0).convertTo(raw, CV_32FC3, 1.0 / 255.0);
  const cv::Mat k = (cv::Mat_<double>(3, 3) << 50, 0, 19.5, 0, 50, 14.5, 0, 0, 1);
  cv::Mat expected;
  cv::undistort(raw, expected, k, dist, k);
  EXPECT_LT(cv::norm(frame.images[0], expected, cv::NORM_L1) / (40 * 30 * 3), 0.01);
  EXPECT_GT(cv::norm(frame.images[0], raw, cv::NORM_INF), 0.2);  // the square moved
}

TEST(Sequence, ReadsDepth) {
  const fs::path dir = TestDir();
  TestSequence t;
  for (auto& [key, entry] : t.scene_camera[0].items()) entry["depth_scale"] = 0.5;
  t.Write(dir);
  fs::create_directories(dir / "cam0" / "depth");
  for (int f = 0; f < 3; ++f) {
    cv::Mat depth(30, 40, CV_16UC1, cv::Scalar(2000 + f));
    depth.at<uint16_t>(0, 0) = 0;
    cv::imwrite((dir / "cam0" / "depth" / fmt::format("{:06d}.png", f)).string(), depth);
  }
  const Sequence seq = Sequence::Open(dir.string());
  EXPECT_TRUE(seq.has_depth());
  const Frame frame = seq.ReadFrame(1);
  ASSERT_EQ(frame.depths.size(), 2u);
  ASSERT_EQ(frame.depths[0].type(), CV_32FC1);
  EXPECT_FLOAT_EQ(frame.depths[0].at<float>(5, 5), 2001 * 0.5 * 1e-3);  // metres
  EXPECT_EQ(frame.depths[0].at<float>(0, 0), 0.0f);
  EXPECT_TRUE(frame.depths[1].empty());  // cam1 has no depth folder
}

TEST(Sequence, ReadsJpegImages) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.Write(dir);
  for (int c = 0; c < 2; ++c) {
    for (int f = 0; f < 3; ++f) {
      const fs::path png = dir / fmt::format("cam{}", c) / "rgb" / fmt::format("{:06d}.png", f);
      cv::imwrite(fs::path(png).replace_extension(".jpg").string(), cv::imread(png.string()));
      fs::remove(png);
    }
  }
  const Sequence seq = Sequence::Open(dir.string());
  EXPECT_EQ(seq.ReadFrame(0).images[0].cols, 40);
}

// --- Faults in the middle of a stream: ReadFrame throws, TryReadFrame goes on ----------

// Cuts `file` to `bytes` bytes, as an interrupted copy leaves it.
void Truncate(const fs::path& file, std::uintmax_t bytes) {
  ASSERT_GT(fs::file_size(file), bytes);
  fs::resize_file(file, bytes);
}

TEST(SequenceFaults, DroppedImageIsReadAsMissing) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.Write(dir);
  fs::remove(dir / "cam1" / "rgb" / "000002.png");
  const Sequence seq = Sequence::Open(dir.string());  // a warning, not an error
  EXPECT_EQ(seq.num_frames(), 3);
  ExpectError([&] { seq.ReadFrame(2); }, {"cam1/rgb/000002.png", "not found"});
  const Frame frame = seq.TryReadFrame(2);
  EXPECT_EQ(frame.frame_id, 2);
  ASSERT_EQ(frame.images.size(), 2u);
  EXPECT_FALSE(frame.images[0].empty());
  EXPECT_TRUE(frame.images[1].empty());
  ASSERT_EQ(frame.errors.size(), 1u);
  EXPECT_EQ(frame.errors[0].camera, 1);
  EXPECT_FALSE(frame.errors[0].depth);
  EXPECT_THAT(frame.errors[0].file, HasSubstr("cam1/rgb/000002.png"));
  EXPECT_THAT(frame.errors[0].message, HasSubstr("000002.png"));
  // The neighbours are complete.
  EXPECT_TRUE(seq.TryReadFrame(1).errors.empty());
  EXPECT_FALSE(seq.TryReadFrame(1).images[1].empty());
}

TEST(SequenceFaults, TruncatedImageIsReadAsMissing) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.width = 160;  // large enough that half the file cuts into the pixel data
  t.height = 120;
  for (json& cam : t.scene_camera) {
    for (auto& [key, entry] : cam.items()) entry["cam_K"] = {200.0, 0, 79.5, 0, 200.0, 59.5, 0, 0, 1};
  }
  t.Write(dir);
  const fs::path file = dir / "cam0" / "rgb" / "000001.png";
  Truncate(file, fs::file_size(file) / 2);
  const Sequence seq = Sequence::Open(dir.string());
  ExpectError([&] { seq.ReadFrame(1); }, {"cam0/rgb/000001.png", "not a readable image"});
  const Frame frame = seq.TryReadFrame(1);
  EXPECT_TRUE(frame.images[0].empty());
  ASSERT_FALSE(frame.images[1].empty());
  EXPECT_EQ(frame.images[1].cols, 160);
  ASSERT_EQ(frame.errors.size(), 1u);
  EXPECT_EQ(frame.errors[0].camera, 0);
  EXPECT_THAT(frame.errors[0].message, HasSubstr("000001.png"));
  // An empty file is as unreadable.
  Truncate(file, 0);
  EXPECT_TRUE(seq.TryReadFrame(1).images[0].empty());
  EXPECT_EQ(seq.TryReadFrame(1).errors.size(), 1u);
  EXPECT_TRUE(seq.TryReadFrame(2).errors.empty());
}

TEST(SequenceFaults, WrongSizeAndMissingDepthAreReadAsMissing) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.Write(dir);
  cv::imwrite((dir / "cam1" / "rgb" / "000002.png").string(), TestImage(41, 30, 2, 1));
  fs::create_directories(dir / "cam0" / "depth");
  for (int f : {0, 2}) {  // frame 1's depth dropped
    cv::imwrite((dir / "cam0" / "depth" / fmt::format("{:06d}.png", f)).string(),
                cv::Mat(30, 40, CV_16UC1, cv::Scalar(1000)));
  }
  const Sequence seq = Sequence::Open(dir.string());
  const Frame size_fault = seq.TryReadFrame(2);
  EXPECT_TRUE(size_fault.images[1].empty());
  EXPECT_FALSE(size_fault.images[0].empty());
  EXPECT_FALSE(size_fault.depths[0].empty());
  ASSERT_EQ(size_fault.errors.size(), 1u);
  EXPECT_THAT(size_fault.errors[0].message, HasSubstr("41x30"));
  const Frame depth_fault = seq.TryReadFrame(1);
  EXPECT_FALSE(depth_fault.images[0].empty());  // the colour image is still there
  EXPECT_TRUE(depth_fault.depths[0].empty());
  ASSERT_EQ(depth_fault.errors.size(), 1u);
  EXPECT_TRUE(depth_fault.errors[0].depth);
  EXPECT_THAT(depth_fault.errors[0].file, HasSubstr("cam0/depth/000001.png"));
  ExpectError([&] { seq.ReadFrame(1); }, {"cam0/depth/000001.png"});
  ExpectError([&] { seq.TryReadFrame(3); }, {"frame index 3"});  // a broken contract
}

// --- Bad input: each throws unseen::Error naming the file and the field ---------------

TEST(SequenceBadInput, MissingFolder) {
  ExpectError([] { Sequence::Open("/nonexistent/unseen/seq"); },
              {"/nonexistent/unseen/seq", "not found"});
  const fs::path dir = TestDir();
  ExpectError([&] { Sequence::Open(dir.string()); }, {dir.string(), "not a sequence folder"});
}

TEST(SequenceBadInput, MissingCameraFolder) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.sequence["cameras"].push_back("cam7");
  t.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); }, {"sequence.json", "cam7", "no folder"});
}

TEST(SequenceBadInput, MalformedJson) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.Write(dir);
  std::ofstream(dir / "cam1" / "scene_camera.json") << "{\"0\": {\"cam_K\": [1, 2,";
  ExpectError([&] { Sequence::Open(dir.string()); },
              {"cam1/scene_camera.json", "malformed JSON", "parse error"});
  std::ofstream(dir / "sequence.json") << "{\"cameras\": [\"cam0\"] oops}";
  ExpectError([&] { Sequence::Open(dir.string()); }, {"sequence.json", "malformed JSON"});
}

TEST(SequenceBadInput, SequenceJsonFields) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.sequence.erase("cameras");
  t.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); }, {"sequence.json", "\"cameras\"", "missing"});
  TestSequence u;
  u.sequence["reference_camera"] = "cam5";
  u.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); }, {"sequence.json", "reference_camera", "cam5"});
  TestSequence v;
  v.sequence["fps"] = -3;
  v.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); }, {"sequence.json", "\"fps\"", "-3"});
  TestSequence w;
  w.sequence["object"]["model"] = "models/none.ply";
  w.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); }, {"sequence.json", "object.model", "none.ply"});
}

TEST(SequenceBadInput, CamKMissing) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.scene_camera[1]["2"].erase("cam_K");
  t.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); },
              {"cam1/scene_camera.json frame 2", "\"cam_K\"", "missing"});
}

TEST(SequenceBadInput, CamKWrongLength) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.scene_camera[0]["1"]["cam_K"] = {50.0, 0, 19.5, 0, 50.0, 14.5};
  t.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); },
              {"cam0/scene_camera.json frame 1", "\"cam_K\"", "6 values", "expected 9"});
}

TEST(SequenceBadInput, CamKNotPinhole) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.scene_camera[0]["0"]["cam_K"] = {50.0, 0.5, 19.5, 0, 50.0, 14.5, 0, 0, 1};
  t.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); },
              {"cam0/scene_camera.json frame 0", "\"cam_K\"", "skew"});
}

TEST(SequenceBadInput, IntrinsicsChangePerFrame) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.scene_camera[1]["2"]["cam_K"][0] = 60.0;
  t.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); },
              {"cam1/scene_camera.json frame 2", "fixed intrinsics", "60"});
}

TEST(SequenceBadInput, RigCameraMoves) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.scene_camera[1]["1"]["cam_t_w2c"][1] = 5.0;
  t.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); },
              {"cam1/scene_camera.json frame 1", "cam_t_w2c", "static"});
}

TEST(SequenceBadInput, FrameIdsDiffer) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.scene_camera[1].erase("1");
  t.scene_gt[1].erase("1");
  t.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); },
              {"cam1/scene_camera.json", "camera cam1 lacks frame 1"});
  TestSequence u;
  u.scene_camera[1]["3"] = u.scene_camera[1]["2"];
  u.Write(dir);
  cv::imwrite((dir / "cam1" / "rgb" / "000003.png").string(), TestImage(40, 30, 3, 1));
  ExpectError([&] { Sequence::Open(dir.string()); }, {"cam1/scene_camera.json", "has frame 3"});
}

TEST(SequenceBadInput, CameraWithoutAnyImage) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.Write(dir);
  for (int f = 0; f < 3; ++f) fs::remove(dir / "cam1" / "rgb" / fmt::format("{:06d}.png", f));
  ExpectError([&] { Sequence::Open(dir.string()); }, {"cam1/rgb", "frame 0", "000000.png"});
}

TEST(SequenceBadInput, WrongImageSize) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.Write(dir);
  cv::imwrite((dir / "cam1" / "rgb" / "000002.png").string(), TestImage(41, 30, 2, 1));
  const Sequence seq = Sequence::Open(dir.string());
  seq.ReadFrame(1);
  ExpectError([&] { seq.ReadFrame(2); }, {"cam1/rgb/000002.png", "41x30", "40x30", "cam1"});
}

TEST(SequenceBadInput, NaNInGroundTruth) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.Write(dir);
  // JSON has no NaN literal; files written by Python's json module contain "NaN", which is
  // malformed JSON, and a null where a number belongs is the other form.
  std::string text = t.scene_gt[0].dump();
  const size_t at = text.find("20.0");
  ASSERT_NE(at, std::string::npos) << text;
  text.replace(at, 4, "NaN");
  std::ofstream(dir / "cam0" / "scene_gt.json") << text;
  ExpectError([&] { Sequence::Open(dir.string()); }, {"cam0/scene_gt.json", "malformed JSON"});
  TestSequence u;
  u.scene_gt[0]["2"][1]["cam_t_m2c"][0] = nullptr;
  u.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); },
              {"cam0/scene_gt.json frame 2", "\"cam_t_m2c\"", "null"});
}

TEST(SequenceBadInput, NonOrthonormalRotation) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.scene_gt[1]["1"][1]["cam_R_m2c"] = {1, 0, 0, 0, 1, 0.2, 0, 0, 1};
  t.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); },
              {"cam1/scene_gt.json frame 1", "cam_R_m2c", "orthonormal"});
  TestSequence u;
  u.scene_camera[0]["0"]["cam_R_w2c"] = {1, 0, 0, 0, 1, 0, 0, 0, 1.5};
  u.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); },
              {"cam0/scene_camera.json frame 0", "cam_R_w2c", "orthonormal"});
}

TEST(SequenceBadInput, GroundTruthMissingField) {
  const fs::path dir = TestDir();
  TestSequence t;
  t.scene_gt[0]["0"][1].erase("cam_R_m2c");
  t.Write(dir);
  ExpectError([&] { Sequence::Open(dir.string()); },
              {"cam0/scene_gt.json frame 0", "\"cam_R_m2c\"", "missing"});
}

// --- Video files and image folders ----------------------------------------------------

PinholeCamera SmallCamera() {
  PinholeCamera camera;
  camera.fx = camera.fy = 60.0;
  camera.cx = 31.5;
  camera.cy = 23.5;
  return camera;  // width/height 0: taken from the frames
}

TEST(SequenceVideo, ReadsMjpegAvi) {
  const fs::path path = TestDir() / "clip.avi";
  {
    cv::VideoWriter writer(path.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25.0,
                           cv::Size(64, 48));
    ASSERT_TRUE(writer.isOpened());
    for (int f = 0; f < 12; ++f) {
      cv::Mat image(48, 64, CV_8UC3, cv::Scalar(20 * f, 100, 200 - 10 * f));
      writer.write(image);
    }
  }
  const Sequence seq = Sequence::OpenVideo(path.string(), SmallCamera(), 25.0);
  EXPECT_EQ(seq.num_frames(), 12);
  EXPECT_EQ(seq.rig().size(), 1);
  EXPECT_EQ(seq.rig().cameras[0].name, "cam0");
  EXPECT_EQ(seq.rig().cameras[0].intrinsics.width, 64);
  EXPECT_FALSE(seq.has_ground_truth());
  EXPECT_FALSE(seq.GroundTruth(0).has_value());
  // Sequential, then a backwards seek, then forwards again.
  for (int f : {0, 1, 2, 7, 3, 11}) {
    const Frame frame = seq.ReadFrame(f);
    EXPECT_EQ(frame.frame_id, f);
    EXPECT_NEAR(frame.time_s, f / 25.0, 1e-12);
    ASSERT_EQ(frame.images[0].type(), CV_32FC3);
    const cv::Scalar mean = cv::mean(frame.images[0]);
    EXPECT_NEAR(mean[0], 20 * f / 255.0, 0.03) << "frame " << f;
    EXPECT_NEAR(mean[2], (200 - 10 * f) / 255.0, 0.03) << "frame " << f;
  }
  PinholeCamera wrong = SmallCamera();
  wrong.width = 320;
  wrong.height = 240;
  ExpectError([&] { Sequence::OpenVideo(path.string(), wrong); }, {"clip.avi", "64x48", "320x240"});
  ExpectError(
      [&] { Sequence::OpenVideo((path.parent_path() / "none.avi").string(), SmallCamera()); },
      {"none.avi", "not found"});
  std::ofstream(path.parent_path() / "junk.avi") << "not a video";
  ExpectError(
      [&] { Sequence::OpenVideo((path.parent_path() / "junk.avi").string(), SmallCamera()); },
      {"junk.avi"});
}

TEST(SequenceImageFolder, ReadsSortedImages) {
  const fs::path dir = TestDir();
  const std::vector<std::string> names = {"b_002.png", "a_001.jpg", "c_003.bmp", "d_004.tif"};
  for (size_t i = 0; i < names.size(); ++i) {
    cv::imwrite((dir / names[i]).string(), cv::Mat(48, 64, CV_8UC3, cv::Scalar(50.0 * i, 0, 0)));
  }
  std::ofstream(dir / "notes.txt") << "ignored";
  const Sequence seq = Sequence::OpenImageFolder(dir.string(), SmallCamera(), 15.0);
  ASSERT_EQ(seq.num_frames(), 4);
  EXPECT_DOUBLE_EQ(seq.fps(), 15.0);
  // Sorted by name: a_001 (i=1), b_002 (i=0), c_003 (i=2), d_004 (i=3).
  const double expected[] = {50, 0, 100, 150};
  for (int f = 0; f < 4; ++f) {
    EXPECT_NEAR(cv::mean(seq.ReadFrame(f).images[0])[0], expected[f] / 255.0, 0.02);
  }
  cv::imwrite((dir / "e_005.png").string(), cv::Mat(40, 64, CV_8UC3));
  const Sequence grown = Sequence::OpenImageFolder(dir.string(), SmallCamera());
  ExpectError([&] { grown.ReadFrame(4); }, {"e_005.png", "64x40", "64x48"});
  const fs::path empty = dir / "empty";
  fs::create_directories(empty);
  ExpectError([&] { Sequence::OpenImageFolder(empty.string(), SmallCamera()); },
              {"empty", "no images"});
}

}  // namespace
}  // namespace unseen
