// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include <filesystem>
#include <fstream>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "unseen/io/sequence.h"
#include "unseen/util/error.h"
#include "unseen/util/testing.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using ::testing::HasSubstr;

fs::path TestDir() { return testing::TestDir("sequence_writer"); }

using testing::ExpectError;

json ReadJson(const fs::path& path) {
  std::ifstream in(path);
  return json::parse(in);
}

Rig TwoCameraRig() {
  Rig rig;
  for (int c = 0; c < 2; ++c) {
    RigCamera camera;
    camera.name = "cam" + std::to_string(c);
    camera.intrinsics.width = 48;
    camera.intrinsics.height = 32;
    camera.intrinsics.fx = camera.intrinsics.fy = 70.0 + c;
    camera.intrinsics.cx = 23.5;
    camera.intrinsics.cy = 15.5;
    camera.world_from_cam = Rigid3d(ExpSO3(Eigen::Vector3d(0.0, 0.1 * c, 0.02)),
                                    Eigen::Vector3d(0.1 * c - 0.05, 0.01, 0.0));
    rig.cameras.push_back(camera);
  }
  return rig;
}

struct SyntheticFrame {
  std::vector<cv::Mat> images, depths, masks;
  Rigid3d world_from_obj;
};

// Images on the 8-bit grid (so PNG is exact), depth in [0.3, 4] m with holes, a pose.
SyntheticFrame MakeFrame(const Rig& rig, std::mt19937* rng) {
  SyntheticFrame f;
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_real_distribution<float> depth(0.3f, 4.0f);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (const RigCamera& camera : rig.cameras) {
    const int w = camera.intrinsics.width, h = camera.intrinsics.height;
    cv::Mat image(h, w, CV_32FC3), d(h, w, CV_32FC1), mask(h, w, CV_8UC1);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        image.at<cv::Vec3f>(y, x) =
            cv::Vec3f(byte(*rng) / 255.f, byte(*rng) / 255.f, byte(*rng) / 255.f);
        d.at<float>(y, x) = (x + y) % 7 == 0 ? 0.0f : depth(*rng);
        mask.at<uint8_t>(y, x) = x > w / 2 ? 255 : 0;
      }
    }
    f.images.push_back(image);
    f.depths.push_back(d);
    f.masks.push_back(mask);
  }
  f.world_from_obj =
      Rigid3d(Eigen::Quaterniond(normal(*rng), normal(*rng), normal(*rng), normal(*rng)),
              Eigen::Vector3d(0.1 * normal(*rng), 0.1 * normal(*rng), 1.0 + 0.1 * normal(*rng)));
  return f;
}

TEST(SequenceWriter, RoundTrip) {
  const fs::path dir = TestDir() / "seq";
  const Rig rig = TwoCameraRig();
  SequenceWriterOptions options;
  options.fps = 24.0;
  options.obj_id = 4;
  options.depth_scale = 0.1;
  options.reference_camera = 1;
  options.notes = "round trip";
  std::mt19937 rng(3);
  std::vector<SyntheticFrame> frames;
  {
    SequenceWriter writer(dir.string(), rig, options);
    for (int i = 0; i < 4; ++i) {
      frames.push_back(MakeFrame(rig, &rng));
      const SyntheticFrame& f = frames.back();
      // Frame 2 without ground truth; frame 3 without depth for cam0.
      std::vector<cv::Mat> depths = f.depths;
      if (i == 3) depths[0] = cv::Mat();
      writer.WriteFrame(i, f.images, depths,
                        i == 2 ? std::nullopt : std::optional<Rigid3d>(f.world_from_obj), f.masks);
    }
    writer.Finish();
  }

  // The DATASET.md layout.
  for (const char* file :
       {"sequence.json", "cam0/rgb/000000.png", "cam1/rgb/000003.png", "cam0/depth/000000.png",
        "cam1/mask_visib/000002_000000.png", "cam0/scene_camera.json", "cam1/scene_gt.json"}) {
    EXPECT_TRUE(fs::is_regular_file(dir / file)) << file;
  }
  // Frame 3 had no depth for cam0: Finish() wrote an empty (all-zero) depth image.
  const cv::Mat none = cv::imread((dir / "cam0/depth/000003.png").string(), cv::IMREAD_ANYDEPTH);
  ASSERT_EQ(none.type(), CV_16UC1);
  EXPECT_EQ(cv::countNonZero(none), 0);
  const json seq_json = ReadJson(dir / "sequence.json");
  EXPECT_EQ(seq_json["cameras"], json({"cam0", "cam1"}));
  EXPECT_EQ(seq_json["reference_camera"], "cam1");
  EXPECT_EQ(seq_json["object"]["obj_id"], 4);
  EXPECT_EQ(seq_json["notes"], "round trip");
  const json gt_json = ReadJson(dir / "cam1/scene_gt.json");
  EXPECT_FALSE(gt_json.contains("2"));
  const Rigid3d cam_from_obj = rig.cameras[1].cam_from_world() * frames[0].world_from_obj;
  EXPECT_NEAR(gt_json["0"][0]["cam_t_m2c"][2].get<double>(), cam_from_obj.translation().z() * 1e3,
              1e-9);
  const cv::Mat depth16 = cv::imread((dir / "cam0/depth/000001.png").string(), cv::IMREAD_ANYDEPTH);
  EXPECT_EQ(depth16.type(), CV_16UC1);
  EXPECT_NEAR(depth16.at<uint16_t>(0, 1), frames[1].depths[0].at<float>(0, 1) * 1e4, 0.5);

  // Read back.
  const Sequence seq = Sequence::Open(dir.string());
  EXPECT_EQ(seq.num_frames(), 4);
  EXPECT_DOUBLE_EQ(seq.fps(), 24.0);
  EXPECT_EQ(seq.obj_id(), 4);
  EXPECT_EQ(seq.reference_camera(), 1);
  EXPECT_TRUE(seq.has_depth());
  for (int c = 0; c < 2; ++c) {
    const RigCamera& read = seq.rig().cameras[c];
    EXPECT_EQ(read.name, rig.cameras[c].name);
    EXPECT_EQ(read.intrinsics.width, 48);
    EXPECT_DOUBLE_EQ(read.intrinsics.fx, rig.cameras[c].intrinsics.fx);
    const PoseDifference d = Difference(read.world_from_cam, rig.cameras[c].world_from_cam);
    EXPECT_LT(d.translation, 1e-9);
    EXPECT_LT(d.rotation_rad, 1e-9);
  }
  for (int i = 0; i < 4; ++i) {
    SCOPED_TRACE(i);
    for (int c = 0; c < 2; ++c) {
      const std::optional<Rigid3d> gt = seq.GroundTruthFromCamera(i, c);
      ASSERT_EQ(gt.has_value(), i != 2);
      if (gt) {
        const PoseDifference d = Difference(*gt, frames[i].world_from_obj);
        EXPECT_LT(d.translation, 1e-6);
        EXPECT_LT(d.rotation_rad, 1e-6);
      }
    }
    const Frame frame = seq.ReadFrame(i);
    for (int c = 0; c < 2; ++c) {
      EXPECT_LT(cv::norm(frame.images[c], frames[i].images[c], cv::NORM_INF), 1e-6);
      if (i == 3 && c == 0) {
        EXPECT_EQ(cv::countNonZero(frame.depths[c]), 0);
        continue;
      }
      // Within half a depth step (depth_scale mm), holes stay holes.
      EXPECT_LE(cv::norm(frame.depths[c], frames[i].depths[c], cv::NORM_INF),
                0.5 * options.depth_scale * 1e-3 + 1e-6);
      EXPECT_EQ(frame.depths[c].at<float>(0, 0), 0.0f);
    }
  }
}

TEST(SequenceWriter, JpegImagesAndModel) {
  const fs::path dir = TestDir() / "seq";
  Rig rig = TwoCameraRig();
  rig.cameras.resize(1);
  rig.cameras[0].intrinsics.distortion = {0.01, -0.002, 0.0, 0.0, 0.0};
  SequenceWriterOptions options;
  options.image_extension = ".jpg";
  std::mt19937 rng(5);
  SyntheticFrame f = MakeFrame(rig, &rng);
  for (int y = 0; y < 32; ++y) {  // smooth, as JPEG expects
    for (int x = 0; x < 48; ++x)
      f.images[0].at<cv::Vec3f>(y, x) = cv::Vec3f(x / 48.f, y / 32.f, 0.5f);
  }
  // A 100 x 60 x 40 mm box with vertex colours.
  Mesh box;
  for (int i = 0; i < 8; ++i) {
    box.vertices.emplace_back((i & 1 ? 0.05f : -0.05f), (i & 2 ? 0.03f : -0.03f),
                              (i & 4 ? 0.02f : -0.02f));
    box.colors_bgr.emplace_back(i / 8.0f, 0.5f, 1.0f - i / 8.0f);
  }
  box.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                   {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  {
    SequenceWriter writer(dir.string(), rig, options);
    writer.WriteModel(box);
    writer.WriteFrame(7, f.images, {}, f.world_from_obj);
  }  // Finish() by the destructor
  EXPECT_TRUE(fs::is_regular_file(dir / "cam0/rgb/000007.jpg"));
  EXPECT_FALSE(fs::exists(dir / "cam0/depth"));
  const json info = ReadJson(dir / "models/models_info.json");
  EXPECT_NEAR(info["1"]["diameter"].get<double>(), std::sqrt(100.0 * 100 + 60 * 60 + 40 * 40),
              1e-3);
  EXPECT_NEAR(info["1"]["min_x"].get<double>(), -50.0, 1e-3);
  EXPECT_NEAR(info["1"]["size_y"].get<double>(), 60.0, 1e-3);
  const json camera_json = ReadJson(dir / "cam0/scene_camera.json");
  EXPECT_EQ(camera_json["7"]["dist"].size(), 5u);

  const Sequence seq = Sequence::Open(dir.string());
  EXPECT_EQ(seq.num_frames(), 1);
  EXPECT_EQ(seq.frame_id(0), 7);
  EXPECT_FALSE(seq.has_depth());
  EXPECT_THAT(seq.model_path(), HasSubstr("models/obj_000001.ply"));
  const Mesh model = seq.LoadModel();
  Eigen::Vector3f min, max;
  model.BoundingBox(&min, &max);
  EXPECT_TRUE(min.isApprox(Eigen::Vector3f(-0.05f, -0.03f, -0.02f), 1e-5f));
  EXPECT_TRUE(max.isApprox(Eigen::Vector3f(0.05f, 0.03f, 0.02f), 1e-5f));
  EXPECT_EQ(model.num_triangles(), 12);
  // JPEG is lossy: close to, not equal to, the written (distorted) image; undistortion
  // then shifts it slightly.
  const Frame frame = seq.ReadFrame(0);
  EXPECT_EQ(frame.images[0].cols, 48);
  const PinholeCamera& k = rig.cameras[0].intrinsics;
  const cv::Mat k_mat = (cv::Mat_<double>(3, 3) << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  cv::Mat expected;
  cv::undistort(f.images[0], expected, k_mat, k.distortion, k_mat);
  EXPECT_LT(cv::norm(frame.images[0], expected, cv::NORM_L1) / (48 * 32 * 3), 0.02);
}

TEST(SequenceWriter, RejectsBadInput) {
  const fs::path dir = TestDir();
  const Rig rig = TwoCameraRig();
  SequenceWriterOptions bad;
  bad.image_extension = ".gif";
  ExpectError([&] { SequenceWriter((dir / "a").string(), rig, bad); }, {"image_extension", ".gif"});
  bad = SequenceWriterOptions();
  bad.depth_scale = 0.0;
  ExpectError([&] { bad.Check(); }, {"depth_scale"});
  bad = SequenceWriterOptions();
  bad.reference_camera = 2;
  ExpectError([&] { SequenceWriter((dir / "a").string(), rig, bad); }, {"reference_camera 2"});
  Rig twins = rig;
  twins.cameras[1].name = "cam0";
  ExpectError([&] { SequenceWriter((dir / "a").string(), twins, {}); }, {"cam0", "twice"});

  SequenceWriter writer((dir / "b").string(), rig, {});
  std::mt19937 rng(1);
  const SyntheticFrame f = MakeFrame(rig, &rng);
  ExpectError([&] { writer.WriteFrame(0, {f.images[0]}, {}, std::nullopt); },
              {"frame 0", "1 images", "2 cameras"});
  std::vector<cv::Mat> wrong = f.images;
  wrong[1] = cv::Mat(10, 10, CV_32FC3);
  ExpectError([&] { writer.WriteFrame(0, wrong, {}, std::nullopt); },
              {"frame 0", "cam1", "10x10", "48x32"});
  std::vector<cv::Mat> bad_depth = f.depths;
  bad_depth[0].convertTo(bad_depth[0], CV_16UC1);
  ExpectError([&] { writer.WriteFrame(0, f.images, bad_depth, std::nullopt); },
              {"frame 0", "cam0", "CV_32FC1"});
  writer.WriteFrame(0, f.images, {}, std::nullopt);
  ExpectError([&] { writer.WriteFrame(0, f.images, {}, std::nullopt); }, {"frame 0", "twice"});
}

}  // namespace
}  // namespace unseen
