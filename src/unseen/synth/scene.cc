// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/synth/scene.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "unseen/image/image_io.h"
#include "unseen/mesh/mesh_io.h"
#include "unseen/mesh/primitives.h"
#include "unseen/synth/scene_yaml.h"
#include "unseen/util/error.h"
#include "unseen/util/files.h"

namespace unseen {

namespace {

constexpr double kDegToRad = M_PI / 180.0;

using scene_yaml::ColorRgb;
using scene_yaml::Context;
using scene_yaml::Direction;
using scene_yaml::Field;
using scene_yaml::FilePath;
using scene_yaml::Mm;
using scene_yaml::Vec3Mm;

// ---- cameras ------------------------------------------------------------------------

// world_from_cam from position_mm and either yaw/pitch/roll (R = Ry(yaw) Rx(pitch)
// Rz(roll): yaw about the vertical world y axis, positive turning the view to the right,
// pitch about the camera x axis, positive looking down, roll about the optical axis) or
// look_at_mm (+ up, default [0, -1, 0], i.e. world y points down).
Rigid3d ParseWorldFromCam(const Field& f) {
  f.ExpectKeys({"position_mm", "yaw_deg", "pitch_deg", "roll_deg", "look_at_mm", "up"});
  const Eigen::Vector3d position =
      f.Has("position_mm") ? Vec3Mm(f.Child("position_mm")) : Eigen::Vector3d::Zero();
  if (f.Has("look_at_mm")) {
    if (f.Has("yaw_deg") || f.Has("pitch_deg") || f.Has("roll_deg")) {
      f.Fail("give either look_at_mm or yaw/pitch/roll, not both");
    }
    const Field target_field = f.Child("look_at_mm");
    const Eigen::Vector3d target = Vec3Mm(target_field);
    const Eigen::Vector3d up =
        f.Has("up") ? Direction(f.Child("up")) : Eigen::Vector3d(0.0, -1.0, 0.0);
    const Eigen::Vector3d z = target - position;
    if (z.norm() < 1e-9) target_field.Fail("look-at point equals the camera position");
    const Eigen::Vector3d zn = z.normalized();
    Eigen::Vector3d down = -(up - up.dot(zn) * zn);
    if (down.norm() < 1e-6) f.Child("up").Fail("up is parallel to the viewing direction");
    down.normalize();
    Eigen::Matrix3d r;
    r.col(0) = down.cross(zn);
    r.col(1) = down;
    r.col(2) = zn;
    return Rigid3d(Eigen::Quaterniond(r), position);
  }
  auto angle = [&](const char* key) {
    return f.Has(key) ? f.Child(key).Double() * kDegToRad : 0.0;
  };
  const Eigen::Quaterniond r =
      Eigen::Quaterniond(Eigen::AngleAxisd(angle("yaw_deg"), Eigen::Vector3d::UnitY())) *
      Eigen::Quaterniond(Eigen::AngleAxisd(-angle("pitch_deg"), Eigen::Vector3d::UnitX())) *
      Eigen::Quaterniond(Eigen::AngleAxisd(angle("roll_deg"), Eigen::Vector3d::UnitZ()));
  return Rigid3d(r, position);
}

// Intrinsics: width, height and fx, fy, cx, cy, or hfov_deg (square pixels, principal
// point at the image centre unless cx/cy are given).
PinholeCamera ParseIntrinsics(const Field& f) {
  PinholeCamera c;
  c.width = f.Child("width").Int();
  c.height = f.Child("height").Int();
  if (c.width <= 0 || c.width > 16384)
    f.Child("width").Fail("must be in [1, 16384], got {}", c.width);
  if (c.height <= 0 || c.height > 16384)
    f.Child("height").Fail("must be in [1, 16384], got {}", c.height);
  if (f.Has("hfov_deg")) {
    if (f.Has("fx") || f.Has("fy")) f.Fail("give either hfov_deg or fx/fy, not both");
    const Field h = f.Child("hfov_deg");
    const double hfov = h.InRange(h.Double(), 1.0, 179.0) * kDegToRad;
    c.fx = c.fy = 0.5 * c.width / std::tan(0.5 * hfov);
  } else {
    const Field fx = f.Child("fx");
    c.fx = fx.Positive(fx.Double());
    c.fy = f.Has("fy") ? f.Child("fy").Positive(f.Child("fy").Double()) : c.fx;
  }
  c.cx = f.Has("cx") ? f.Child("cx").Double() : 0.5 * (c.width - 1);
  c.cy = f.Has("cy") ? f.Child("cy").Double() : 0.5 * (c.height - 1);
  return c;
}

RigCamera ParseCamera(const Field& f, const std::string& default_name) {
  f.ExpectKeys({"name", "width", "height", "fx", "fy", "cx", "cy", "hfov_deg", "world_from_cam"});
  RigCamera cam;
  cam.name = f.Has("name") ? f.Child("name").String() : default_name;
  if (cam.name.empty() || cam.name.find('/') != std::string::npos) {
    f.Child("name").Fail("camera name must be a non-empty folder name, got {}",
                         f.Child("name").Text());
  }
  cam.intrinsics = ParseIntrinsics(f);
  if (f.Has("world_from_cam")) cam.world_from_cam = ParseWorldFromCam(f.Child("world_from_cam"));
  return cam;
}

// `camera_line`: count cameras evenly spaced from from_mm to to_mm, all with the same
// intrinsics and orientation, named <name_prefix><i>.
std::vector<RigCamera> ParseCameraLine(const Field& f) {
  f.ExpectKeys({"count", "from_mm", "to_mm", "name_prefix", "width", "height", "fx", "fy", "cx",
                "cy", "hfov_deg", "yaw_deg", "pitch_deg", "roll_deg"});
  const Field count_field = f.Child("count");
  const int count = count_field.Int();
  if (count < 1 || count > 64) count_field.Fail("must be in [1, 64], got {}", count);
  const Eigen::Vector3d from = Vec3Mm(f.Child("from_mm"));
  const Eigen::Vector3d to = Vec3Mm(f.Child("to_mm"));
  const std::string prefix = f.Has("name_prefix") ? f.Child("name_prefix").String() : "cam";
  const PinholeCamera intrinsics = ParseIntrinsics(f);
  auto angle = [&](const char* key) {
    return f.Has(key) ? f.Child(key).Double() * kDegToRad : 0.0;
  };
  const Eigen::Quaterniond r =
      Eigen::Quaterniond(Eigen::AngleAxisd(angle("yaw_deg"), Eigen::Vector3d::UnitY())) *
      Eigen::Quaterniond(Eigen::AngleAxisd(-angle("pitch_deg"), Eigen::Vector3d::UnitX())) *
      Eigen::Quaterniond(Eigen::AngleAxisd(angle("roll_deg"), Eigen::Vector3d::UnitZ()));
  std::vector<RigCamera> cams;
  for (int i = 0; i < count; ++i) {
    const double a = count == 1 ? 0.0 : static_cast<double>(i) / (count - 1);
    RigCamera cam;
    cam.name = prefix + std::to_string(i);
    cam.intrinsics = intrinsics;
    cam.world_from_cam = Rigid3d(r, from + a * (to - from));
    cams.push_back(cam);
  }
  return cams;
}

// ---- object ---------------------------------------------------------------------------

ObjectSpec ParseObject(const Field& f, const Context& ctx) {
  ObjectSpec o;
  const Field type_field = f.Child("type");
  const std::string type = type_field.String();
  if (type == "lettered_cube") {
    f.ExpectKeys({"type", "edge_mm", "texture_px", "scale"});
    o.type = ObjectSpec::Type::kLetteredCube;
    if (f.Has("edge_mm")) o.edge_m = Mm(f.Child("edge_mm"));
    if (!(o.edge_m > 0.0))
      f.Child("edge_mm").Fail("must be positive, got {}", f.Child("edge_mm").Text());
    if (f.Has("texture_px")) {
      o.texture_px = f.Child("texture_px").Int();
      if (o.texture_px < 16 || o.texture_px > 4096) {
        f.Child("texture_px").Fail("must be in [16, 4096], got {}", o.texture_px);
      }
    }
  } else if (type == "textured_sphere") {
    f.ExpectKeys({"type", "radius_mm", "rings", "segments", "texture", "scale"});
    o.type = ObjectSpec::Type::kTexturedSphere;
    if (f.Has("radius_mm")) o.radius_m = f.Child("radius_mm").Positive(Mm(f.Child("radius_mm")));
    if (f.Has("rings")) o.rings = f.Child("rings").Int();
    if (f.Has("segments")) o.segments = f.Child("segments").Int();
    if (o.rings < 3 || o.rings > 1000)
      f.Child("rings").Fail("must be in [3, 1000], got {}", o.rings);
    if (o.segments < 3 || o.segments > 2000) {
      f.Child("segments").Fail("must be in [3, 2000], got {}", o.segments);
    }
    if (f.Has("texture")) o.texture_path = FilePath(f.Child("texture"), ctx);
  } else if (type == "textured_box") {
    f.ExpectKeys({"type", "size_mm", "textures", "scale"});
    o.type = ObjectSpec::Type::kTexturedBox;
    if (f.Has("size_mm")) {
      const Field s = f.Child("size_mm");
      o.size_m = Vec3Mm(s);
      if (!(o.size_m.minCoeff() > 0.0)) s.Fail("sizes must be positive, got {}", s.Text());
    }
    if (f.Has("textures")) {
      const Field t = f.Child("textures");
      t.ExpectKeys({"+x", "-x", "+y", "-y", "+z", "-z"});
      const char* faces[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
      for (int i = 0; i < 6; ++i) {
        if (t.Has(faces[i])) o.face_texture_paths[i] = FilePath(t.Child(faces[i]), ctx);
      }
    }
  } else if (type == "mesh") {
    f.ExpectKeys({"type", "path", "unit_mm", "scale"});
    o.type = ObjectSpec::Type::kMesh;
    o.mesh_path = FilePath(f.Child("path"), ctx);
    // unit_mm: millimetres per file unit (1 for BOP models, 1000 for a file in metres).
    if (f.Has("unit_mm")) o.mesh_scale_to_m = f.Child("unit_mm").Positive(Mm(f.Child("unit_mm")));
  } else {
    type_field.Fail("unknown object type {} (lettered_cube, textured_sphere, textured_box, mesh)",
                    type_field.Text());
  }
  if (f.Has("scale")) o.scale = f.Child("scale").Positive(f.Child("scale").Double());
  return o;
}

// ---- trajectories ---------------------------------------------------------------------

std::vector<AxisRotation> ParseRotationSteps(const Field& f) {
  if (!f.IsSequence())
    f.Fail("expected a list of {{axis: [x, y, z], deg: angle}}, got {}", f.Text());
  std::vector<AxisRotation> steps;
  for (size_t i = 0; i < f.size(); ++i) {
    const Field s = f.Index(i);
    s.ExpectKeys({"axis", "deg"});
    AxisRotation step;
    step.axis = Direction(s.Child("axis"));
    // Bounded so that the angle in radians, and its sine and cosine, stay finite.
    step.angle_deg = s.Child("deg").InRange(s.Child("deg").Double(), -1e6, 1e6);
    steps.push_back(step);
  }
  return steps;
}

std::shared_ptr<const Trajectory> ParseTrajectory(const Field& f, const Context& ctx, double fps) {
  const Field type_field = f.Child("type");
  const std::string type = type_field.String();
  if (type == "waypoints") {
    f.ExpectKeys({"type", "origin_mm", "waypoints_mm", "speed_mm_s", "velocity_mm_s",
                  "start_time_s", "initial_rotation", "spin"});
    WaypointTrajectoryOptions o;
    o.origin_m = f.Has("origin_mm") ? Vec3Mm(f.Child("origin_mm")) : Eigen::Vector3d::Zero();
    const Field w = f.Child("waypoints_mm");
    if (!w.IsSequence() || w.size() == 0) w.Fail("expected a non-empty list of [x, y, z] points");
    o.waypoints_m.clear();
    for (size_t i = 0; i < w.size(); ++i) o.waypoints_m.push_back(Vec3Mm(w.Index(i)));
    if (f.Has("speed_mm_s") == f.Has("velocity_mm_s")) {
      f.Fail("give exactly one of speed_mm_s and velocity_mm_s");
    }
    if (f.Has("speed_mm_s")) {
      o.speed_m_s = f.Child("speed_mm_s").Positive(Mm(f.Child("speed_mm_s")));
    } else {
      // Table 4.3's "initial velocity" (vx, vz) in the top view, or (vx, vy, vz): travelled
      // as the constant path speed |v|.
      const Field v = f.Child("velocity_mm_s");
      const auto comps = v.Numbers(3, 2);
      double sq = 0.0;
      for (double c : comps) sq += c * c;
      o.speed_m_s = std::sqrt(sq) * 1e-3;
      if (!(o.speed_m_s > 0.0)) v.Fail("velocity must not be zero, got {}", v.Text());
    }
    if (f.Has("start_time_s"))
      o.start_time_s = f.Child("start_time_s").NonNegative(f.Child("start_time_s").Double());
    if (f.Has("initial_rotation")) {
      o.initial_rotation = ComposeRotations(ParseRotationSteps(f.Child("initial_rotation")));
    }
    if (f.Has("spin")) {
      const Field s = f.Child("spin");
      s.ExpectKeys({"axis", "rate_rad_s", "frame"});
      if (s.Has("axis")) o.spin.axis = Direction(s.Child("axis"));
      // Bounded so that the angle turned by the end of any sequence stays finite.
      if (s.Has("rate_rad_s")) {
        const Field rate = s.Child("rate_rad_s");
        o.spin.rate_rad_s = rate.InRange(rate.Double(), -1e3, 1e3);
      }
      if (s.Has("frame")) {
        const Field fr = s.Child("frame");
        const std::string frame = fr.String();
        if (frame != "object" && frame != "world")
          fr.Fail("must be 'object' or 'world', got {}", fr.Text());
        o.spin.world_frame = frame == "world";
      }
    }
    try {
      return std::make_shared<WaypointTrajectory>(o);
    } catch (const Error& e) {
      f.Fail("{}", e.what());
    }
  }
  if (type == "pose_file") {
    f.ExpectKeys({"type", "path", "time_offset_s"});
    const std::string path = FilePath(f.Child("path"), ctx);
    const double offset = f.Has("time_offset_s") ? f.Child("time_offset_s").Double() : 0.0;
    try {
      return LoadPoseFileTrajectory(path, fps, offset);
    } catch (const Error& e) {
      f.Child("path").Fail("{}", e.what());
    }
  }
  if (type == "static") {
    f.ExpectKeys({"type", "position_mm", "rotation"});
    const Eigen::Vector3d p = Vec3Mm(f.Child("position_mm"));
    const std::vector<AxisRotation> steps =
        f.Has("rotation") ? ParseRotationSteps(f.Child("rotation")) : std::vector<AxisRotation>();
    try {
      return std::make_shared<StaticTrajectory>(Rigid3d(ComposeRotations(steps), p));
    } catch (const Error& e) {
      f.Fail("{}", e.what());
    }
  }
  type_field.Fail("unknown trajectory type {} (waypoints, pose_file, static)", type_field.Text());
}

// ---- background, lights, occluders, sensor, depth ------------------------------------

BackgroundSpec ParseBackground(const Field& f, const Context& ctx) {
  BackgroundSpec b;
  const Field type_field = f.Child("type");
  const std::string type = type_field.String();
  if (type == "color") {
    f.ExpectKeys({"type", "color_rgb", "distance_mm", "brightness"});
    b.type = BackgroundSpec::Type::kColor;
    if (f.Has("color_rgb")) b.color_bgr = ColorRgb(f.Child("color_rgb"));
  } else if (type == "image") {
    f.ExpectKeys({"type", "path", "distance_mm", "brightness"});
    b.type = BackgroundSpec::Type::kImage;
    b.image_path = FilePath(f.Child("path"), ctx);
  } else if (type == "clutter") {
    f.ExpectKeys({"type", "distance_mm", "brightness", "width_px", "height_px"});
    b.type = BackgroundSpec::Type::kClutter;
    if (f.Has("width_px")) b.clutter_width_px = f.Child("width_px").Int();
    if (f.Has("height_px")) b.clutter_height_px = f.Child("height_px").Int();
    if (b.clutter_width_px < 16 || b.clutter_width_px > 8192) {
      f.Child("width_px").Fail("must be in [16, 8192], got {}", b.clutter_width_px);
    }
    if (b.clutter_height_px < 16 || b.clutter_height_px > 8192) {
      f.Child("height_px").Fail("must be in [16, 8192], got {}", b.clutter_height_px);
    }
  } else {
    type_field.Fail("unknown background type {} (color, image, clutter)", type_field.Text());
  }
  if (f.Has("distance_mm"))
    b.distance_m = f.Child("distance_mm").Positive(Mm(f.Child("distance_mm")));
  if (f.Has("brightness"))
    b.brightness = f.Child("brightness").NonNegative(f.Child("brightness").Double());
  return b;
}

LightingSpec ParseLights(const Field& f) {
  f.ExpectKeys({"ambient", "sources"});
  LightingSpec l;
  if (f.Has("ambient")) l.ambient = f.Child("ambient").NonNegative(f.Child("ambient").Double());
  if (!f.Has("sources")) return l;
  const Field sources = f.Child("sources");
  if (!sources.IsSequence()) sources.Fail("expected a list of lights, got {}", sources.Text());
  for (size_t i = 0; i < sources.size(); ++i) {
    const Field s = sources.Index(i);
    LightSpec light;
    const Field type_field = s.Child("type");
    const std::string type = type_field.String();
    if (type == "directional") {
      s.ExpectKeys({"type", "direction", "intensity", "color_rgb", "cast_shadows"});
      light.type = LightSpec::Type::kDirectional;
      light.direction = Direction(s.Child("direction"));
    } else if (type == "point") {
      s.ExpectKeys({"type", "position_mm", "velocity_mm_s", "intensity", "reference_distance_mm",
                    "color_rgb", "cast_shadows"});
      light.type = LightSpec::Type::kPoint;
      light.position_m = Vec3Mm(s.Child("position_mm"));
      if (s.Has("velocity_mm_s")) light.velocity_m_s = Vec3Mm(s.Child("velocity_mm_s"));
      if (s.Has("reference_distance_mm")) {
        light.reference_distance_m =
            s.Child("reference_distance_mm").Positive(Mm(s.Child("reference_distance_mm")));
      }
    } else {
      type_field.Fail("unknown light type {} (directional, point)", type_field.Text());
    }
    if (s.Has("intensity"))
      light.intensity = s.Child("intensity").NonNegative(s.Child("intensity").Double());
    if (s.Has("color_rgb")) light.color_bgr = ColorRgb(s.Child("color_rgb"));
    if (s.Has("cast_shadows")) light.cast_shadows = s.Child("cast_shadows").Bool();
    l.lights.push_back(light);
  }
  return l;
}

OccluderSpec ParseOccluder(const Field& f, const Context& ctx, double fps) {
  OccluderSpec o;
  const Field type_field = f.Child("type");
  const std::string type = type_field.String();
  if (type == "bar") {
    f.ExpectKeys({"type", "size_mm", "start_mm", "end_mm", "speed_mm_s", "start_time_s",
                  "color_rgb", "shaded"});
    o.type = OccluderSpec::Type::kBar;
    if (f.Has("size_mm")) {
      o.size_m = Vec3Mm(f.Child("size_mm"));
      if (!(o.size_m.minCoeff() > 0.0))
        f.Child("size_mm").Fail("sizes must be positive, got {}", f.Child("size_mm").Text());
    }
    o.start_m = Vec3Mm(f.Child("start_mm"));
    o.end_m = Vec3Mm(f.Child("end_mm"));
    if (f.Has("speed_mm_s"))
      o.speed_m_s = f.Child("speed_mm_s").Positive(Mm(f.Child("speed_mm_s")));
    if (f.Has("start_time_s"))
      o.start_time_s = f.Child("start_time_s").NonNegative(f.Child("start_time_s").Double());
    if (f.Has("color_rgb")) o.color_bgr = ColorRgb(f.Child("color_rgb"));
    if (f.Has("shaded")) o.shaded = f.Child("shaded").Bool();
  } else if (type == "object") {
    f.ExpectKeys({"type", "object", "trajectory"});
    o.type = OccluderSpec::Type::kObject;
    o.object = ParseObject(f.Child("object"), ctx);
    o.trajectory = ParseTrajectory(f.Child("trajectory"), ctx, fps);
  } else {
    type_field.Fail("unknown occluder type {} (bar, object)", type_field.Text());
  }
  return o;
}

SensorSpec ParseSensor(const Field& f) {
  f.ExpectKeys(
      {"noise_sigma", "blur_sigma_px", "gain", "antialias", "image_format", "jpeg_quality"});
  SensorSpec s;
  if (f.Has("noise_sigma"))
    s.noise_sigma = f.Child("noise_sigma").InRange(f.Child("noise_sigma").Double(), 0.0, 128.0);
  if (f.Has("blur_sigma_px"))
    s.blur_sigma_px =
        f.Child("blur_sigma_px").InRange(f.Child("blur_sigma_px").Double(), 0.0, 50.0);
  if (f.Has("gain")) s.gain = f.Child("gain").Positive(f.Child("gain").Double());
  if (f.Has("antialias")) {
    const Field a = f.Child("antialias");
    s.antialias = a.Int();
    if (s.antialias != 1 && s.antialias != 3 && s.antialias != 5) {
      a.Fail("must be 1, 3 or 5 (odd, so that the centre sub-sample is the pixel centre), got {}",
             a.Text());
    }
  }
  if (f.Has("image_format")) {
    const Field fmt_field = f.Child("image_format");
    s.image_format = fmt_field.String();
    if (s.image_format != "png" && s.image_format != "jpg")
      fmt_field.Fail("must be 'png' or 'jpg', got {}", fmt_field.Text());
  }
  if (f.Has("jpeg_quality")) {
    const Field q = f.Child("jpeg_quality");
    s.jpeg_quality = q.Int();
    if (s.jpeg_quality < 1 || s.jpeg_quality > 100) q.Fail("must be in [1, 100], got {}", q.Text());
  }
  return s;
}

DepthSpec ParseDepth(const Field& f) {
  f.ExpectKeys({"enabled", "noise_sigma_mm", "hole_fraction", "depth_scale_mm"});
  DepthSpec d;
  d.enabled = f.Has("enabled") ? f.Child("enabled").Bool() : true;
  if (f.Has("noise_sigma_mm"))
    d.noise_sigma_mm =
        f.Child("noise_sigma_mm").InRange(f.Child("noise_sigma_mm").Double(), 0.0, 1000.0);
  if (f.Has("hole_fraction"))
    d.hole_fraction = f.Child("hole_fraction").InRange(f.Child("hole_fraction").Double(), 0.0, 0.9);
  if (f.Has("depth_scale_mm"))
    d.depth_scale_mm =
        f.Child("depth_scale_mm").InRange(f.Child("depth_scale_mm").Double(), 1e-3, 100.0);
  return d;
}

}  // namespace

// ---- public -------------------------------------------------------------------------

Mesh BuildObjectMesh(const ObjectSpec& spec) {
  Mesh mesh;
  switch (spec.type) {
    case ObjectSpec::Type::kMesh:
      mesh = LoadMesh(spec.mesh_path, spec.mesh_scale_to_m);
      break;
    case ObjectSpec::Type::kLetteredCube:
      mesh = MakeLetteredCube(spec.edge_m, spec.texture_px);
      break;
    case ObjectSpec::Type::kTexturedSphere:
      mesh = MakeTexturedSphere(
          spec.radius_m, spec.rings, spec.segments,
          spec.texture_path.empty() ? cv::Mat() : LoadColorImage(spec.texture_path));
      break;
    case ObjectSpec::Type::kTexturedBox: {
      std::array<cv::Mat, 6> textures;
      for (int i = 0; i < 6; ++i) {
        if (!spec.face_texture_paths[i].empty()) {
          textures[i] = LoadColorImage(spec.face_texture_paths[i]);
        }
      }
      mesh = MakeTexturedBox(spec.size_m, textures);
      break;
    }
  }
  if (spec.scale != 1.0) mesh.Scale(static_cast<float>(spec.scale));
  mesh.Check("object mesh");
  return mesh;
}

int Scene::NumFrames() const {
  if (frames > 0) return frames;
  UNSEEN_CHECK(trajectory != nullptr, "{}: scene has no trajectory", path);
  const double end = trajectory->EndTimeS();
  UNSEEN_CHECK(std::isfinite(end),
               "{}: 'frames' is needed: the trajectory never ends (a pure spin)", path);
  const double n = std::floor(end * fps + 1e-9) + 1.0;
  UNSEEN_CHECK(n >= 1.0 && n <= 1e6, "{}: trajectory end {} s gives {} frames at {} fps", path, end,
               n, fps);
  return static_cast<int>(n);
}

void Scene::Check() const {
  UNSEEN_CHECK(std::isfinite(fps) && fps > 0.0, "{}: fps {} must be positive", path, fps);
  UNSEEN_CHECK(frames == -1 || frames > 0, "{}: frames {} must be positive (or -1 = until end)",
               path, frames);
  rig.Check();
  UNSEEN_CHECK(rig.size() > 0, "{}: no cameras", path);
  UNSEEN_CHECK(reference_camera >= 0 && reference_camera < rig.size(),
               "{}: reference camera index {} out of range [0, {})", path, reference_camera,
               rig.size());
  UNSEEN_CHECK(trajectory != nullptr, "{}: no trajectory", path);
  UNSEEN_CHECK(sensor.antialias == 1 || sensor.antialias == 3 || sensor.antialias == 5,
               "{}: sensor.antialias {} must be 1, 3 or 5", path, sensor.antialias);
  UNSEEN_CHECK(sensor.noise_sigma >= 0.0 && sensor.blur_sigma_px >= 0.0 && sensor.gain > 0.0,
               "{}: sensor noise {}, blur {} px, gain {} out of range", path, sensor.noise_sigma,
               sensor.blur_sigma_px, sensor.gain);
  UNSEEN_CHECK(sensor.image_format == "png" || sensor.image_format == "jpg",
               "{}: sensor.image_format '{}' must be png or jpg", path, sensor.image_format);
  UNSEEN_CHECK(background.distance_m > 0.0, "{}: background distance {} m must be positive", path,
               background.distance_m);
  UNSEEN_CHECK(depth.hole_fraction >= 0.0 && depth.hole_fraction < 1.0 &&
                   depth.noise_sigma_mm >= 0.0 && depth.depth_scale_mm > 0.0,
               "{}: depth options out of range", path);
  UNSEEN_CHECK(model_scale > 0.0 && std::isfinite(model_scale),
               "{}: model_scale {} must be positive", path, model_scale);
  for (size_t i = 0; i < occluders.size(); ++i) {
    UNSEEN_CHECK(occluders[i].type != OccluderSpec::Type::kObject || occluders[i].trajectory,
                 "{}: occluder {} has no trajectory", path, i);
  }
}

Scene ParseScene(const std::string& text, const std::string& path, const std::string& base_dir) {
  Context ctx{path, base_dir};
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    ThrowError("{}: malformed YAML at line {}, column {}: {}", path, e.mark.line + 1,
               e.mark.column + 1, e.msg);
  }
  const Field f(root, "", &ctx.file);
  if (!root.IsMap()) f.Fail("the scene must be a YAML mapping");
  f.ExpectKeys({"name", "notes", "seed", "fps", "frames", "cameras", "camera_line",
                "reference_camera", "object", "trajectory", "background", "lights", "occluders",
                "sensor", "depth", "masks", "model_scale"});

  Scene s;
  s.path = path;
  s.name = f.Has("name") ? f.Child("name").String() : std::filesystem::path(path).stem().string();
  if (f.Has("notes")) s.notes = f.Child("notes").String();
  if (f.Has("seed")) s.seed = f.Child("seed").UInt64();
  if (f.Has("fps")) s.fps = f.Child("fps").InRange(f.Child("fps").Double(), 0.1, 10000.0);
  if (f.Has("frames")) {
    const Field fr = f.Child("frames");
    if (fr.IsScalar() && fr.node().Scalar() == "until_end") {
      s.frames = -1;
    } else {
      s.frames = fr.Int();
      if (s.frames < 1 || s.frames > 1000000)
        fr.Fail("must be in [1, 1000000] or 'until_end', got {}", fr.Text());
    }
  }

  // Cameras: a list, and/or a line of identical cameras.
  if (!f.Has("cameras") && !f.Has("camera_line")) f.Fail("needs 'cameras' or 'camera_line'");
  if (f.Has("cameras")) {
    const Field cams = f.Child("cameras");
    if (!cams.IsSequence() || cams.size() == 0) cams.Fail("expected a non-empty list of cameras");
    for (size_t i = 0; i < cams.size(); ++i) {
      s.rig.cameras.push_back(ParseCamera(cams.Index(i), "cam" + std::to_string(i)));
    }
  }
  if (f.Has("camera_line")) {
    for (auto& c : ParseCameraLine(f.Child("camera_line"))) s.rig.cameras.push_back(c);
  }
  for (int i = 0; i < s.rig.size(); ++i) {
    for (int j = 0; j < i; ++j) {
      if (s.rig.cameras[i].name == s.rig.cameras[j].name) {
        f.Fail("two cameras are called '{}'", s.rig.cameras[i].name);
      }
    }
  }
  try {
    s.rig.Check();
  } catch (const Error& e) {
    f.Fail("cameras: {}", e.what());
  }
  if (f.Has("reference_camera")) {
    const Field r = f.Child("reference_camera");
    s.reference_camera = s.rig.Find(r.String());
    if (s.reference_camera < 0) r.Fail("no camera called {}", r.Text());
  } else {
    s.reference_camera = 0;
  }

  s.object = ParseObject(f.Child("object"), ctx);
  s.trajectory = ParseTrajectory(f.Child("trajectory"), ctx, s.fps);
  if (f.Has("background")) s.background = ParseBackground(f.Child("background"), ctx);
  if (f.Has("lights")) s.lighting = ParseLights(f.Child("lights"));
  if (f.Has("occluders")) {
    const Field occ = f.Child("occluders");
    if (!occ.IsSequence()) occ.Fail("expected a list of occluders, got {}", occ.Text());
    for (size_t i = 0; i < occ.size(); ++i)
      s.occluders.push_back(ParseOccluder(occ.Index(i), ctx, s.fps));
  }
  if (f.Has("sensor")) s.sensor = ParseSensor(f.Child("sensor"));
  if (f.Has("depth")) s.depth = ParseDepth(f.Child("depth"));
  if (f.Has("masks")) s.write_masks = f.Child("masks").Bool();
  if (f.Has("model_scale"))
    s.model_scale = f.Child("model_scale").Positive(f.Child("model_scale").Double());

  if (s.frames < 0 && !std::isfinite(s.trajectory->EndTimeS())) {
    f.Fail("'frames' is needed: the trajectory never ends");
  }
  s.Check();
  return s;
}

Scene LoadScene(const std::string& path) {
  std::ifstream in(path);
  UNSEEN_CHECK(in.good(), "scene file {} cannot be opened", path);
  std::stringstream text;
  text << in.rdbuf();
  const std::filesystem::path p(path);
  const std::string base = p.has_parent_path() ? p.parent_path().string() : ".";
  return ParseScene(text.str(), path, base);
}

}  // namespace unseen
