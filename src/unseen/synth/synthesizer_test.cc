// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/synth/synthesizer.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "unseen/io/sequence.h"
#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

// A small, fast scene: 160x80 px, 34 deg HFOV, the lettered cube on a short path.
std::string TinyScene(const std::string& extra = "") {
  return R"(
name: tiny
seed: 5
fps: 30
frames: 4
cameras:
  - {name: cam0, width: 160, height: 80, hfov_deg: 34}
  - {name: cam1, width: 160, height: 80, hfov_deg: 34, world_from_cam: {position_mm: [50, 0, 0]}}
object: {type: lettered_cube, edge_mm: 96, texture_px: 64}
trajectory:
  type: waypoints
  origin_mm: [-20, 10, 900]
  waypoints_mm: [[0, 0, 0], [60, 0, 40]]
  speed_mm_s: 300
  initial_rotation: [{axis: [1, 0, 0], deg: 20}, {axis: [0, 1, 0], deg: 30}]
  spin: {axis: [0, 1, 0], rate_rad_s: 2.0}
background: {type: clutter, width_px: 400, height_px: 200, distance_mm: 1500}
lights:
  ambient: 0.3
  sources:
    - {type: point, position_mm: [300, -400, 200], intensity: 0.8}
sensor: {noise_sigma: 2}
)" + extra;
}

fs::path TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("unseen_synth_test_" + name);
  fs::remove_all(dir);
  return dir;
}

std::string ReadBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The object rendered at its ground-truth pose at the camera's own resolution.
RenderBuffers RenderTruth(const Mesh& mesh, const RigCamera& cam, const Rigid3d& world_from_obj) {
  RenderBuffers b;
  RenderOptions o;
  o.write_color = false;
  Render(mesh, cam.intrinsics, cam.cam_from_world() * world_from_obj, cam.intrinsics.ImageRect(), o,
         &b);
  return b;
}

TEST(Synthesize, WritesSequenceThatReadsBackWithTruth) {
  const Scene scene = ParseScene(TinyScene("depth: {enabled: true}\n"), "tiny.yaml", ".");
  const fs::path dir = TempDir("readback");
  const SynthSummary summary = Synthesize(scene, dir.string(), {.progress = false});
  EXPECT_EQ(summary.frames, 4);
  EXPECT_EQ(summary.cameras, 2);

  const Sequence seq = Sequence::Open(dir.string());
  ASSERT_EQ(seq.num_frames(), 4);
  ASSERT_EQ(seq.rig().size(), 2);
  EXPECT_DOUBLE_EQ(seq.fps(), 30.0);
  EXPECT_TRUE(seq.has_depth());
  EXPECT_TRUE(seq.rig().cameras[1].world_from_cam.translation().isApprox(
      Eigen::Vector3d(0.05, 0, 0), 1e-9));
  const Mesh model = seq.LoadModel();
  const Synthesizer synth(scene);
  EXPECT_EQ(model.num_triangles(), synth.object_mesh().num_triangles());

  for (int k = 0; k < seq.num_frames(); ++k) {
    const Rigid3d truth = scene.trajectory->WorldFromObj(k / 30.0);
    for (int c = 0; c < 2; ++c) {
      const auto gt = seq.GroundTruthFromCamera(k, c);
      ASSERT_TRUE(gt.has_value());
      EXPECT_LT((gt->translation() - truth.translation()).norm(), 1e-6);
      EXPECT_LT(AngleBetween(gt->rotation(), truth.rotation()), 1e-6);
    }
    const Frame frame = seq.ReadFrame(k);
    for (int c = 0; c < 2; ++c) {
      const RigCamera& cam = seq.rig().cameras[c];
      const RenderBuffers b = RenderTruth(synth.object_mesh(), cam, truth);
      // mask_visib is the object's coverage at pixel centres: the plain render's mask.
      const fs::path mask_path =
          dir / cam.name / "mask_visib" / fmt::format("{:06d}_000000.png", k);
      const cv::Mat mask = cv::imread(mask_path.string(), cv::IMREAD_UNCHANGED);
      ASSERT_FALSE(mask.empty()) << mask_path;
      cv::Mat diff;
      cv::compare(mask, b.mask, diff, cv::CMP_NE);
      const int covered = cv::countNonZero(b.mask);
      EXPECT_GT(covered, 500);
      EXPECT_LE(cv::countNonZero(diff), covered / 200) << "frame " << k << " camera " << c;
      // Depth: the rendered depth on the object (16-bit at 0.1 mm), the background plane
      // (z = 1.5 m for these unrotated cameras) elsewhere.
      const cv::Mat& depth = frame.depths[c];
      ASSERT_EQ(depth.type(), CV_32FC1);
      int checked = 0;
      for (int v = 0; v < depth.rows; ++v) {
        for (int u = 0; u < depth.cols; ++u) {
          if (b.mask.at<uint8_t>(v, u) && mask.at<uint8_t>(v, u)) {
            EXPECT_NEAR(depth.at<float>(v, u), b.depth.at<float>(v, u), 1e-4);
            ++checked;
          } else if (!b.mask.at<uint8_t>(v, u)) {
            EXPECT_NEAR(depth.at<float>(v, u), 1.5, 1e-4);
          }
        }
      }
      EXPECT_GT(checked, 500);
      // The image is the right size, noisy but not blank.
      ASSERT_EQ(frame.images[c].size(), cv::Size(160, 80));
      cv::Scalar mean, stddev;
      cv::meanStdDev(frame.images[c], mean, stddev);
      EXPECT_GT(stddev[0], 0.05);
    }
  }
  fs::remove_all(dir);
}

TEST(Synthesize, DeterministicForSeed) {
  const Scene scene = ParseScene(TinyScene(), "tiny.yaml", ".");
  const fs::path a = TempDir("det_a"), b = TempDir("det_b"), c = TempDir("det_c");
  Synthesize(scene, a.string(), {.progress = false});
  Synthesize(scene, b.string(), {.progress = false});
  // --frames: a prefix renders the same frames.
  Synthesize(scene, c.string(), {.max_frames = 2, .progress = false});
  int compared = 0;
  for (const auto& entry : fs::recursive_directory_iterator(a)) {
    if (!entry.is_regular_file()) continue;
    const fs::path rel = fs::relative(entry.path(), a);
    ASSERT_TRUE(fs::exists(b / rel)) << rel;
    EXPECT_EQ(ReadBytes(entry.path()), ReadBytes(b / rel)) << rel;
    ++compared;
  }
  EXPECT_GT(compared, 10);
  EXPECT_EQ(ReadBytes(a / "cam1" / "rgb" / "000001.png"),
            ReadBytes(c / "cam1" / "rgb" / "000001.png"));
  EXPECT_FALSE(fs::exists(c / "cam1" / "rgb" / "000002.png"));

  // Another seed changes the noise.
  const fs::path d = TempDir("det_d");
  Synthesize(scene, d.string(), {.max_frames = 1, .seed = 99, .progress = false});
  EXPECT_NE(ReadBytes(a / "cam0" / "rgb" / "000000.png"),
            ReadBytes(d / "cam0" / "rgb" / "000000.png"));
  for (const auto& p : {a, b, c, d}) fs::remove_all(p);
}

TEST(Synthesizer, OccluderIsExcludedFromMask) {
  // A white bar 600 mm away, passing over the object's path at frame 2 of 5.
  const Scene scene = ParseScene(TinyScene(R"(occluders:
  - {type: bar, size_mm: [30, 400, 10], start_mm: [-120, 0, 600], end_mm: [80, 0, 600]}
)"),
                                 "tiny.yaml", ".");
  const Synthesizer synth(scene);
  int hidden_total = 0;
  for (int k = 0; k < synth.num_frames(); ++k) {
    const SynthFrame f = synth.RenderFrame(k);
    const RigCamera& cam = scene.rig.cameras[0];
    const RenderBuffers object = RenderTruth(synth.object_mesh(), cam, f.world_from_obj);
    // Pixels of the object's silhouette hidden in the mask are pure white (the bar).
    int hidden = 0;
    for (int v = 0; v < object.mask.rows; ++v) {
      for (int u = 0; u < object.mask.cols; ++u) {
        if (f.masks[0].at<uint8_t>(v, u)) {
          EXPECT_TRUE(object.mask.at<uint8_t>(v, u));  // never outside the silhouette
        } else if (object.mask.at<uint8_t>(v, u)) {
          ++hidden;
          // The bar is 600 mm away, nearer than the object.
          EXPECT_NEAR(f.clean_depths[0].at<float>(v, u), 0.595, 1e-3);
        }
      }
    }
    hidden_total += hidden;
  }
  EXPECT_GT(hidden_total, 100);
}

TEST(Synthesizer, LightsShadeTheObjectOnly) {
  const Scene dark = ParseScene(TinyScene(), "tiny.yaml", ".");
  Scene lit = dark;
  lit.sensor.noise_sigma = 0.0;
  Scene unlit = lit;
  unlit.lighting.lights.clear();
  // Directional light from behind the camera: every visible face is lit.
  LightSpec frontal;
  frontal.type = LightSpec::Type::kDirectional;
  frontal.direction = Eigen::Vector3d(0, 0, 1);
  frontal.intensity = 0.7;
  lit.lighting.lights = {frontal};
  const SynthFrame a = Synthesizer(unlit).RenderFrame(0);
  const SynthFrame b = Synthesizer(lit).RenderFrame(0);
  cv::Mat not_object;
  cv::bitwise_not(a.masks[0], not_object);
  cv::erode(not_object, not_object, cv::Mat(), cv::Point(-1, -1), 2);  // away from edges
  cv::Mat inside;
  cv::erode(a.masks[0], inside, cv::Mat(), cv::Point(-1, -1), 2);
  const cv::Scalar bg_a = cv::mean(a.images[0], not_object),
                   bg_b = cv::mean(b.images[0], not_object);
  const cv::Scalar obj_a = cv::mean(a.images[0], inside), obj_b = cv::mean(b.images[0], inside);
  for (int ch = 0; ch < 3; ++ch) {
    EXPECT_NEAR(bg_a[ch], bg_b[ch], 1e-6);  // the background is not lit
    // Ambient 0.3 only vs 0.3 + 0.7 cos(angle) > ~0.3 + 0.35.
    EXPECT_GT(obj_b[ch], 1.8 * obj_a[ch]);
  }
}

TEST(Synthesizer, DepthNoiseAndHoles) {
  Scene scene =
      ParseScene(TinyScene("depth: {noise_sigma_mm: 2.0, hole_fraction: 0.1}\n"), "tiny.yaml", ".");
  const SynthFrame f = Synthesizer(scene).RenderFrame(1);
  const cv::Mat& clean = f.clean_depths[0];
  const cv::Mat& noisy = f.depths[0];
  int valid = 0, holes = 0;
  double sum_sq = 0.0;
  for (int v = 0; v < clean.rows; ++v) {
    for (int u = 0; u < clean.cols; ++u) {
      if (clean.at<float>(v, u) <= 0.0f) continue;
      ++valid;
      if (noisy.at<float>(v, u) == 0.0f) {
        ++holes;
      } else {
        const double e = noisy.at<float>(v, u) - clean.at<float>(v, u);
        sum_sq += e * e;
      }
    }
  }
  ASSERT_EQ(valid, clean.rows * clean.cols);  // the background plane fills the view
  EXPECT_NEAR(static_cast<double>(holes) / valid, 0.1, 0.005);
  EXPECT_NEAR(std::sqrt(sum_sq / (valid - holes)), 0.002, 0.0002);
}

TEST(Synthesizer, RejectsBadInput) {
  EXPECT_THROW(SynthOptions{.max_frames = 0}.Check(), Error);
  // A camera looking away from the background plane.
  const Scene scene = ParseScene(TinyScene().replace(TinyScene().find("{position_mm: [50, 0, 0]}"),
                                                     25, "{position_mm: [50, 0, 0], yaw_deg: 180}"),
                                 "tiny.yaml", ".");
  EXPECT_THROW(Synthesizer{scene}, Error);
  // Unwritable output folder.
  const Scene ok = ParseScene(TinyScene(), "tiny.yaml", ".");
  EXPECT_THROW(Synthesize(ok, "/proc/unseen_no_such/dir", {.progress = false}), Error);
}

TEST(Synthesizer, MovingLightChangesShadingOnly) {
  Scene scene = ParseScene(TinyScene(), "tiny.yaml", ".");
  scene.sensor.noise_sigma = 0.0;
  scene.trajectory = std::make_shared<StaticTrajectory>(
      Rigid3d(ExpSO3(Eigen::Vector3d(0.3, 0.5, 0.0)), Eigen::Vector3d(0, 0, 0.9)));
  // A point light sweeping from the far left to the right (30 m/s: 2 m in two frames).
  LightSpec light;
  light.type = LightSpec::Type::kPoint;
  light.position_m = {-1.0, 0.0, 0.5};
  light.velocity_m_s = {30.0, 0.0, 0.0};
  scene.lighting.lights = {light};
  const Synthesizer synth(scene);
  const SynthFrame a = synth.RenderFrame(0), b = synth.RenderFrame(2);
  EXPECT_EQ(cv::countNonZero(a.masks[0] != b.masks[0]), 0);  // nothing moved but the light
  cv::Mat not_object;
  cv::bitwise_not(a.masks[0], not_object);
  cv::erode(not_object, not_object, cv::Mat(), cv::Point(-1, -1), 2);
  cv::Mat diff;
  cv::absdiff(a.images[0], b.images[0], diff);
  EXPECT_LT(cv::norm(diff, cv::NORM_INF, not_object), 1e-6);
  EXPECT_GT(cv::norm(diff, cv::NORM_INF, a.masks[0]), 0.1);
}

// Every shipped scene loads, follows the SPEC 8 camera protocol, and shows the object.
TEST(Synthesizer, ShippedScenesRender) {
  const fs::path dir = fs::path(UNSEEN_SOURCE_DIR) / "scenes";
  int scenes = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(entry.path().string());
    Scene scene = LoadScene(entry.path().string());
    ++scenes;
    EXPECT_DOUBLE_EQ(scene.fps, 30.0);
    for (const RigCamera& cam : scene.rig.cameras) {
      EXPECT_EQ(cam.intrinsics.width, 512);
      EXPECT_EQ(cam.intrinsics.height, 256);
      EXPECT_NEAR(cam.intrinsics.fx, 837.3, 0.05);
      EXPECT_DOUBLE_EQ(cam.intrinsics.cx, 255.5);
      EXPECT_DOUBLE_EQ(cam.intrinsics.cy, 127.5);
    }
    const int frames = scene.NumFrames();
    EXPECT_GE(frames, 20);
    scene.sensor.antialias = 1;  // fast: only visibility is checked here
    const Synthesizer synth(scene);
    for (int k : {0, frames / 2, frames - 1}) {
      const SynthFrame f = synth.RenderFrame(k);
      const int ref = scene.reference_camera;
      EXPECT_GT(cv::countNonZero(f.masks[ref]), 1000) << "frame " << k;
    }
    if (entry.path().stem() == "rig5_fig312") {
      EXPECT_EQ(scene.rig.size(), 5);
      EXPECT_EQ(frames, 240);
      EXPECT_EQ(scene.rig.cameras[scene.reference_camera].name, "cam2");
      EXPECT_TRUE(scene.depth.enabled);
    }
    if (entry.path().stem() == "speed_120_060") {
      // |(120, 60)| = 134.16 mm/s along the 374.7 mm zig-zag: 2.79 s, frames 0..83.
      EXPECT_EQ(frames, 84);
    }
  }
  EXPECT_GE(scenes, 15);
}

}  // namespace
}  // namespace unseen
