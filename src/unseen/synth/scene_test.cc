// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/synth/scene.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "unseen/mesh/mesh_io.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

// True when `text` contains `part` (messages printed on failure).
::testing::AssertionResult HasSubstr(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << text << "' does not contain '" << part << "'";
}

const char* kMinimal = R"(
seed: 7
fps: 30
frames: 12
cameras:
  - name: cam0
    width: 512
    height: 256
    hfov_deg: 34
object: {type: lettered_cube, edge_mm: 96}
trajectory:
  type: waypoints
  origin_mm: [0, 0, 1000]
  waypoints_mm: [[0, 0, 0], [240, 0, 120]]
  speed_mm_s: 60
)";

Scene Parse(const std::string& text) { return ParseScene(text, "test.yaml", "."); }

// The message of the error thrown by parsing `text`, or "" when it parses.
std::string ErrorOf(const std::string& text) {
  try {
    Parse(text);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Scene, ParsesMinimalSceneWithDefaults) {
  const Scene s = Parse(kMinimal);
  EXPECT_EQ(s.seed, 7u);
  EXPECT_EQ(s.NumFrames(), 12);
  ASSERT_EQ(s.rig.size(), 1);
  const PinholeCamera& c = s.rig.cameras[0].intrinsics;
  // SPEC 8: 34 deg HFOV at 512 px -> fx = fy ~ 837.3, principal point at the centre.
  EXPECT_NEAR(c.fx, 837.3, 0.1);
  EXPECT_DOUBLE_EQ(c.fx, c.fy);
  EXPECT_DOUBLE_EQ(c.cx, 255.5);
  EXPECT_DOUBLE_EQ(c.cy, 127.5);
  EXPECT_EQ(s.object.type, ObjectSpec::Type::kLetteredCube);
  EXPECT_DOUBLE_EQ(s.object.edge_m, 0.096);
  EXPECT_TRUE(s.trajectory->WorldFromObj(0.0).translation().isApprox(Eigen::Vector3d(0, 0, 1)));
  EXPECT_EQ(s.background.type, BackgroundSpec::Type::kColor);
  EXPECT_EQ(s.sensor.antialias, 3);
  EXPECT_FALSE(s.depth.enabled);
}

TEST(Scene, FramesUntilTrajectoryEnds) {
  std::string text = kMinimal;
  text.replace(text.find("frames: 12"), 10, "frames: until_end");
  const Scene s = Parse(text);
  // Path length sqrt(240^2 + 120^2) = 268.3 mm at 60 mm/s = 4.47 s -> frames 0..134.
  EXPECT_EQ(s.NumFrames(), 135);
}

TEST(Scene, VelocityIsTravelledAsSpeed) {
  std::string text = kMinimal;
  text.replace(text.find("speed_mm_s: 60"), 14, "velocity_mm_s: [120, 60]");
  const Scene s = Parse(text);
  const auto* w = dynamic_cast<const WaypointTrajectory*>(s.trajectory.get());
  ASSERT_NE(w, nullptr);
  EXPECT_NEAR(w->options().speed_m_s, 0.13416, 1e-5);
}

TEST(Scene, ParsesFullScene) {
  const Scene s = Parse(R"(
name: full
notes: everything
seed: 3
fps: 25
frames: 5
camera_line:
  count: 5
  from_mm: [-100, 0, 0]
  to_mm: [100, 0, 0]
  width: 512
  height: 256
  fx: 837.3
  cx: 255.5
  cy: 127.5
reference_camera: cam2
object: {type: textured_sphere, radius_mm: 60, rings: 10, segments: 20}
trajectory:
  type: waypoints
  origin_mm: [-120, 0, 1000]
  waypoints_mm: [[0, 0, 0], [240, 0, 120], [0, 0, 240]]
  speed_mm_s: 67
  initial_rotation: [{axis: [1, 0, 0], deg: 20}, {axis: [0, 1, 0], deg: 30}]
  spin: {axis: [0, 1, 0], rate_rad_s: 0.18, frame: world}
background: {type: clutter, distance_mm: 1500, brightness: 0.8}
lights:
  ambient: 0.2
  sources:
    - {type: directional, direction: [1, 0.15, 0.35], intensity: 0.9, cast_shadows: true}
    - {type: point, position_mm: [500, -600, 300], velocity_mm_s: [-10, 0, 0], intensity: 0.5,
       reference_distance_mm: 1000, color_rgb: [1, 0.9, 0.8]}
occluders:
  - {type: bar, size_mm: [30, 400, 10], start_mm: [-260, 0, 700], end_mm: [260, 0, 700],
     color_rgb: [1, 1, 1]}
  - type: object
    object: {type: lettered_cube, edge_mm: 50}
    trajectory: {type: static, position_mm: [0, 0, 800], rotation: [{axis: [0, 1, 0], deg: 45}]}
sensor: {noise_sigma: 2, blur_sigma_px: 0.5, gain: 1.5, antialias: 5, image_format: jpg, jpeg_quality: 90}
depth: {noise_sigma_mm: 1.5, hole_fraction: 0.02}
masks: false
model_scale: 1.1
)");
  EXPECT_EQ(s.name, "full");
  EXPECT_DOUBLE_EQ(s.fps, 25.0);
  ASSERT_EQ(s.rig.size(), 5);
  EXPECT_EQ(s.reference_camera, 2);
  EXPECT_EQ(s.rig.cameras[4].name, "cam4");
  EXPECT_TRUE(s.rig.cameras[0].world_from_cam.translation().isApprox(Eigen::Vector3d(-0.1, 0, 0)));
  EXPECT_TRUE(s.rig.cameras[1].world_from_cam.translation().isApprox(Eigen::Vector3d(-0.05, 0, 0)));
  EXPECT_EQ(s.object.type, ObjectSpec::Type::kTexturedSphere);
  EXPECT_EQ(s.object.rings, 10);
  EXPECT_EQ(s.background.type, BackgroundSpec::Type::kClutter);
  EXPECT_DOUBLE_EQ(s.background.distance_m, 1.5);
  ASSERT_EQ(s.lighting.lights.size(), 2u);
  EXPECT_EQ(s.lighting.lights[0].type, LightSpec::Type::kDirectional);
  EXPECT_NEAR(s.lighting.lights[0].direction.norm(), 1.0, 1e-12);
  EXPECT_TRUE(s.lighting.lights[0].cast_shadows);
  EXPECT_FALSE(s.lighting.lights[1].cast_shadows);
  EXPECT_TRUE(s.lighting.lights[1].PositionAt(2.0).isApprox(Eigen::Vector3d(0.48, -0.6, 0.3)));
  // color_rgb [1, 0.9, 0.8] is stored as BGR.
  EXPECT_TRUE(s.lighting.lights[1].color_bgr.isApprox(Eigen::Vector3d(0.8, 0.9, 1.0)));
  ASSERT_EQ(s.occluders.size(), 2u);
  EXPECT_EQ(s.occluders[0].type, OccluderSpec::Type::kBar);
  EXPECT_TRUE(s.occluders[0].size_m.isApprox(Eigen::Vector3d(0.03, 0.4, 0.01)));
  EXPECT_EQ(s.occluders[1].type, OccluderSpec::Type::kObject);
  EXPECT_TRUE(s.occluders[1].trajectory->WorldFromObj(1.0).translation().isApprox(
      Eigen::Vector3d(0, 0, 0.8)));
  EXPECT_EQ(s.sensor.image_format, "jpg");
  EXPECT_EQ(s.sensor.antialias, 5);
  EXPECT_TRUE(s.depth.enabled);
  EXPECT_DOUBLE_EQ(s.depth.noise_sigma_mm, 1.5);
  EXPECT_FALSE(s.write_masks);
  EXPECT_DOUBLE_EQ(s.model_scale, 1.1);
}

TEST(Scene, CameraOrientation) {
  const Scene s = Parse(R"(
frames: 1
cameras:
  - {name: a, width: 64, height: 32, fx: 50, world_from_cam: {position_mm: [0, 0, 0], yaw_deg: 90}}
  - {name: b, width: 64, height: 32, fx: 50,
     world_from_cam: {position_mm: [1000, 0, 0], look_at_mm: [0, 0, 0]}}
  - {name: c, width: 64, height: 32, fx: 50, world_from_cam: {pitch_deg: 30}}
object: {type: lettered_cube}
trajectory: {type: static, position_mm: [0, 0, 1000]}
)");
  // Yaw 90 deg turns the optical axis from +z to +x.
  const Eigen::Vector3d za = s.rig.cameras[0].world_from_cam.rotation() * Eigen::Vector3d::UnitZ();
  EXPECT_TRUE(za.isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  // Looking from +x at the origin: optical axis -x, image down = world down (+y).
  const Rigid3d& b = s.rig.cameras[1].world_from_cam;
  EXPECT_TRUE((b.rotation() * Eigen::Vector3d::UnitZ()).isApprox(-Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_TRUE((b.rotation() * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  // Positive pitch looks down (optical axis gains +y, world down).
  const Eigen::Vector3d zc = s.rig.cameras[2].world_from_cam.rotation() * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(zc.y(), std::sin(30.0 * M_PI / 180.0), 1e-12);
}

TEST(Scene, ErrorsNameFileFieldLineAndValue) {
  std::string text = kMinimal;
  text.replace(text.find("speed_mm_s: 60"), 14, "speed_mm_s: -4");
  std::string msg = ErrorOf(text);
  EXPECT_TRUE(HasSubstr(msg, "test.yaml"));
  EXPECT_TRUE(HasSubstr(msg, "trajectory.speed_mm_s"));
  EXPECT_TRUE(HasSubstr(msg, "line 15"));
  EXPECT_TRUE(HasSubstr(msg, "-4"));

  text = kMinimal;
  text.replace(text.find("hfov_deg: 34"), 12, "hfov_deg: wide");
  msg = ErrorOf(text);
  EXPECT_TRUE(HasSubstr(msg, "cameras[0].hfov_deg"));
  EXPECT_TRUE(HasSubstr(msg, "'wide'"));
}

TEST(Scene, RejectsBadInput) {
  auto replaced = [](const std::string& from, const std::string& to) {
    std::string text = kMinimal;
    const size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
  };
  EXPECT_TRUE(HasSubstr(ErrorOf("seed: [1"), "malformed YAML"));
  EXPECT_TRUE(HasSubstr(ErrorOf("- 1\n- 2\n"), "mapping"));
  EXPECT_TRUE(HasSubstr(ErrorOf(replaced("seed: 7", "sed: 7")), "unknown field 'sed'"));
  EXPECT_TRUE(HasSubstr(ErrorOf(replaced("seed: 7", "seed: -1")), "'seed'"));
  EXPECT_TRUE(HasSubstr(ErrorOf(replaced("frames: 12", "frames: 0")), "frames"));
  EXPECT_TRUE(HasSubstr(ErrorOf(replaced("width: 512", "width: 0")), "cameras[0].width"));
  EXPECT_TRUE(
      HasSubstr(ErrorOf(replaced("    hfov_deg: 34\n", "")), "missing required field 'fx'"));
  EXPECT_TRUE(HasSubstr(ErrorOf(replaced("lettered_cube", "teapot")), "unknown object type"));
  EXPECT_TRUE(HasSubstr(ErrorOf(replaced("edge_mm: 96", "edge_mm: -96")), "object.edge_mm"));
  EXPECT_TRUE(HasSubstr(ErrorOf(replaced("[0, 0, 1000]", "[0, 0]")), "list of 3 numbers"));
  EXPECT_TRUE(HasSubstr(ErrorOf(replaced("[240, 0, 120]", "[240, 0, .nan]")),
                        "trajectory.waypoints_mm[1][2]"));
  EXPECT_TRUE(
      HasSubstr(ErrorOf(replaced("speed_mm_s: 60", "speed_mm_s: 60\n  velocity_mm_s: [1, 2]")),
                "exactly one of"));
  EXPECT_TRUE(
      HasSubstr(ErrorOf(replaced("type: waypoints", "type: spline")), "unknown trajectory type"));
  EXPECT_TRUE(
      HasSubstr(ErrorOf(std::string(kMinimal) + "sensor: {antialias: 2}\n"), "sensor.antialias"));
  EXPECT_TRUE(HasSubstr(ErrorOf(std::string(kMinimal) + "sensor: {image_format: bmp}\n"), "'bmp'"));
  EXPECT_TRUE(
      HasSubstr(ErrorOf(std::string(kMinimal) + "background: {type: image, path: no_such.png}\n"),
                "does not exist"));
  EXPECT_TRUE(HasSubstr(
      ErrorOf(std::string(kMinimal) + "background: {type: color, color_rgb: [2, 0, 0]}\n"),
      "background.color_rgb"));
  EXPECT_TRUE(HasSubstr(ErrorOf(std::string(kMinimal) +
                                "background: {type: image, path: $UNSEEN_NO_SUCH_VAR/a.png}\n"),
                        "UNSEEN_NO_SUCH_VAR"));
  EXPECT_TRUE(HasSubstr(ErrorOf(std::string(kMinimal) + "lights: {sources: [{type: area}]}\n"),
                        "unknown light type"));
  EXPECT_TRUE(HasSubstr(ErrorOf(std::string(kMinimal) +
                                "lights: {sources: [{type: directional, direction: [0, 0, 0]}]}\n"),
                        "lights.sources[0].direction"));
  EXPECT_TRUE(HasSubstr(ErrorOf(std::string(kMinimal) + "depth: {hole_fraction: 1.5}\n"),
                        "depth.hole_fraction"));
  EXPECT_TRUE(
      HasSubstr(ErrorOf(std::string(kMinimal) + "reference_camera: cam9\n"), "no camera called"));
  EXPECT_TRUE(
      HasSubstr(ErrorOf(std::string(kMinimal) + "occluders: [{type: bar, start_mm: [0, 0, 0]}]\n"),
                "missing required field 'end_mm'"));
  EXPECT_TRUE(
      HasSubstr(ErrorOf(std::string(kMinimal) + "cameras2: 1\n"), "unknown field 'cameras2'"));
}

TEST(Scene, LoadsFileAndResolvesRelativePaths) {
  const auto dir = std::filesystem::temp_directory_path() / "unseen_scene_test";
  std::filesystem::create_directories(dir);
  EXPECT_THROW(LoadScene((dir / "missing.yaml").string()), Error);
  {
    std::ofstream(dir / "poses.csv") << "frame,time_s,status,confidence,tx,ty,tz,qx,qy,qz,qw\n"
                                     << "0,0,tracking,1,0,0,1,0,0,0,1\n"
                                     << "1,0.5,tracking,1,0.1,0,1,0,0,0,1\n";
    std::string text = kMinimal;
    const size_t at = text.find("trajectory:");
    text = text.substr(0, at) + "trajectory: {type: pose_file, path: poses.csv}\n";
    std::ofstream(dir / "scene.yaml") << text;
  }
  const Scene s = LoadScene((dir / "scene.yaml").string());
  EXPECT_TRUE(s.trajectory->WorldFromObj(0.25).translation().isApprox(Eigen::Vector3d(0.05, 0, 1)));
  std::filesystem::remove_all(dir);
}

TEST(BuildObjectMesh, BuildsEveryObjectType) {
  const auto dir = std::filesystem::temp_directory_path() / "unseen_scene_objects";
  std::filesystem::create_directories(dir);
  // A mesh file in millimetres and a texture image, referenced relative to the scene.
  ObjectSpec cube;
  cube.edge_m = 0.05;
  SaveMesh(BuildObjectMesh(cube), (dir / "cube_mm.ply").string(), 1000.0);
  cv::imwrite((dir / "tex.png").string(), cv::Mat(32, 64, CV_8UC3, cv::Scalar(10, 200, 30)));
  const std::string base = kMinimal;
  auto object_of = [&](const std::string& object_yaml) {
    std::string text = base;
    const size_t at = text.find("object: {type: lettered_cube, edge_mm: 96}");
    text.replace(at, 42, object_yaml);
    return BuildObjectMesh(ParseScene(text, "objects.yaml", dir.string()).object);
  };
  Eigen::Vector3f lo, hi;
  const Mesh from_file = object_of("object: {type: mesh, path: cube_mm.ply, unit_mm: 1, scale: 2}");
  from_file.BoundingBox(&lo, &hi);
  EXPECT_NEAR(hi.x() - lo.x(), 0.1, 1e-5);  // 50 mm x scale 2, in metres
  const Mesh sphere = object_of(
      "object: {type: textured_sphere, radius_mm: 30, rings: 8, segments: 16, "
      "texture: tex.png}");
  sphere.BoundingBox(&lo, &hi);
  EXPECT_NEAR(hi.z() - lo.z(), 0.06, 1e-5);
  ASSERT_FALSE(sphere.materials.empty());
  const cv::Vec3f texel = sphere.materials[0].texture.at<cv::Vec3f>(5, 5);
  EXPECT_NEAR(texel[1], 200.0 / 255.0, 1e-3);  // the file's green, not the generated globe
  const Mesh box =
      object_of("object: {type: textured_box, size_mm: [40, 20, 10], textures: {+x: tex.png}}");
  box.BoundingBox(&lo, &hi);
  EXPECT_TRUE((hi - lo).isApprox(Eigen::Vector3f(0.04f, 0.02f, 0.01f), 1e-5f));
  EXPECT_EQ(object_of("object: {type: lettered_cube, edge_mm: 96}").num_triangles(), 12);
  // Missing files are named.
  EXPECT_TRUE(HasSubstr(
      ErrorOf(base.substr(0, base.find("object:")) + "object: {type: mesh, path: nothing.ply}\n" +
              base.substr(base.find("trajectory:"))),
      "object.path"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace unseen
