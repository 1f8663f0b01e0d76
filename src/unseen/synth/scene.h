// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Synthetic scene descriptions (YAML) for `unseen synth`: cameras, the object and its
// trajectory, background, lights, occluders, sensor effects and outputs. The field names
// follow the scene.json files the development sequences were rendered from. Lengths in the
// file are millimetres (`_mm`), angles degrees (`_deg`) unless named `_rad`, colours are
// `color_rgb: [r, g, b]` in [0, 1] (stored here as BGR like every colour in unseen).
// World frame: the camera frame convention (x right, y down, z away from the cameras);
// a trajectory's waypoints are in this frame. scenes/README.md documents every field.
//
// Every value is validated when loaded; errors name the YAML file, the field path, its line
// and column, and the offending value.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "unseen/camera/camera.h"
#include "unseen/mesh/mesh.h"
#include "unseen/synth/trajectory.h"

namespace unseen {

// An object to render: a mesh file or one of the built-in primitives (mesh/primitives.h).
struct ObjectSpec {
  enum class Type { kMesh, kLetteredCube, kTexturedSphere, kTexturedBox };
  Type type = Type::kLetteredCube;
  std::string mesh_path;          // kMesh: absolute path
  double mesh_scale_to_m = 1e-3;  // kMesh: file units -> metres (mm files: 0.001)
  double edge_m = 0.096;          // kLetteredCube
  int texture_px = 256;           // kLetteredCube: texture size per face
  double radius_m = 0.06;         // kTexturedSphere
  int rings = 25, segments = 50;  // kTexturedSphere
  std::string texture_path;       // kTexturedSphere: equirectangular image; empty = globe
  Eigen::Vector3d size_m = Eigen::Vector3d(0.16, 0.10, 0.06);  // kTexturedBox (x, y, z)
  std::array<std::string, 6>
      face_texture_paths;  // kTexturedBox: +x -x +y -y +z -z; empty = generated
  double scale = 1.0;      // extra uniform scale applied to the built mesh
};

// Builds the mesh (metres, object frame) of `spec`. Throws unseen::Error naming the file
// for an unreadable mesh or texture.
Mesh BuildObjectMesh(const ObjectSpec& spec);

struct BackgroundSpec {
  enum class Type { kColor, kImage, kClutter };
  Type type = Type::kColor;
  Eigen::Vector3d color_bgr = Eigen::Vector3d::Ones();  // kColor
  std::string image_path;                               // kImage: absolute path
  // A plane facing the cameras at this z (world frame) carries the background; it gives the
  // background its depth and its parallax across a rig. An image is stretched to cover the
  // union of the cameras' views on that plane (with a margin).
  double distance_m = 1.8;
  double brightness = 1.0;      // the background's colours are multiplied by this (>= 0)
  int clutter_width_px = 1600;  // kClutter: generated texture size
  int clutter_height_px = 800;
};

struct LightSpec {
  enum class Type { kDirectional, kPoint };
  Type type = Type::kDirectional;
  // kDirectional: the direction the light travels (from the light into the scene), world
  // frame, unit; e.g. (1, 0.15, 0.35) is a low sun from the left.
  Eigen::Vector3d direction = Eigen::Vector3d(0.0, 1.0, 0.0);
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();    // kPoint: world position at t = 0
  Eigen::Vector3d velocity_m_s = Eigen::Vector3d::Zero();  // kPoint: linear motion
  // Irradiance factor: a surface facing a directional light receives `intensity`; facing a
  // point light at `reference_distance_m`, `intensity` (inverse-square fall-off).
  double intensity = 0.7;
  double reference_distance_m = 1.0;
  Eigen::Vector3d color_bgr = Eigen::Vector3d::Ones();
  bool cast_shadows = false;  // the object shadows itself from this light (shadow map)
  // Position of a point light at time t (seconds).
  Eigen::Vector3d PositionAt(double t_s) const { return position_m + t_s * velocity_m_s; }
};

struct LightingSpec {
  double ambient = 0.35;  // irradiance every surface receives regardless of orientation
  std::vector<LightSpec> lights;
};

struct OccluderSpec {
  enum class Type { kBar, kObject };
  Type type = Type::kBar;
  // kBar: a box of size_m (x, y, z) in colour `color_bgr`, moving from start_m to end_m
  // (world positions of its centre) at speed_m_s; speed 0 = across the whole sequence.
  Eigen::Vector3d size_m = Eigen::Vector3d(0.03, 0.4, 0.01);
  Eigen::Vector3d color_bgr = Eigen::Vector3d::Ones();
  Eigen::Vector3d start_m = Eigen::Vector3d(-0.26, 0.0, 0.7);
  Eigen::Vector3d end_m = Eigen::Vector3d(0.26, 0.0, 0.7);
  double speed_m_s = 0.0;
  double start_time_s = 0.0;  // kBar: the bar waits at start_m until then
  bool shaded = false;        // kBar: false = flat colour (lights ignored)
  // kObject: another object on its own trajectory (lit like the main object).
  ObjectSpec object;
  std::shared_ptr<const Trajectory> trajectory;  // kObject
};

struct SensorSpec {
  double noise_sigma = 0.0;          // additive gaussian noise, grey levels of 255, per channel
  double blur_sigma_px = 0.0;        // gaussian (defocus) blur, pixels; 0 = none
  double gain = 1.0;                 // exposure gain applied before noise (low-light compensation)
  int antialias = 3;                 // supersampling factor, odd (1, 3 or 5), downsampled by area
  std::string image_format = "png";  // "png" or "jpg"
  int jpeg_quality = 92;
};

struct DepthSpec {
  bool enabled = false;         // write 16-bit depth PNGs
  double noise_sigma_mm = 0.0;  // gaussian depth noise, millimetres
  double hole_fraction = 0.0;   // fraction of valid pixels dropped to 0 (in small blobs)
  double depth_scale_mm = 0.1;  // PNG value x depth_scale = millimetres
};

struct Scene {
  std::string path;  // the YAML file (for messages)
  std::string name;
  std::string notes;
  uint64_t seed = 1;
  double fps = 30.0;
  int frames = -1;  // -1: until the trajectory ends (the last frame at or after its end)
  Rig rig;
  int reference_camera = 0;
  ObjectSpec object;
  std::shared_ptr<const Trajectory> trajectory;
  BackgroundSpec background;
  LightingSpec lighting;
  std::vector<OccluderSpec> occluders;
  SensorSpec sensor;
  DepthSpec depth;
  bool write_masks = true;   // camK/mask_visib/<frame>_000000.png
  double model_scale = 1.0;  // the written model is scaled by this (Table 4.2 scale errors)

  // Number of frames to render: `frames`, or enough to reach the trajectory's end
  // (floor(EndTimeS() * fps) + 1). Throws when neither is finite.
  int NumFrames() const;
  // Throws unseen::Error for inconsistent values (the loader checks every field; this
  // re-checks a Scene built or edited in code).
  void Check() const;
};

// Parses a scene from YAML `text`; `path` names it in messages and relative file paths are
// resolved against `base_dir`. Throws unseen::Error naming path, field, line and value.
Scene ParseScene(const std::string& text, const std::string& path, const std::string& base_dir);
// Reads and parses a YAML scene file; relative paths in it are relative to its folder.
Scene LoadScene(const std::string& path);

}  // namespace unseen
