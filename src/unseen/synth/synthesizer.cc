// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/synth/synthesizer.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <filesystem>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>

#include "unseen/image/image_io.h"
#include "unseen/io/sequence.h"
#include "unseen/mesh/primitives.h"
#include "unseen/render/rasterizer.h"
#include "unseen/render/shading.h"
#include "unseen/synth/clutter.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/progress.h"
#include "unseen/util/timer.h"

namespace unseen {

namespace {

// Independent random streams per (seed, frame, camera, purpose).
enum class Stream : uint32_t { kImageNoise = 1, kDepthNoise = 2, kDepthHoles = 3 };

std::mt19937 MakeRng(uint64_t seed, int frame, int camera, Stream stream) {
  std::seed_seq seq{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32),
                    static_cast<uint32_t>(frame), static_cast<uint32_t>(camera),
                    static_cast<uint32_t>(stream)};
  return std::mt19937(seq);
}

// The camera of the supersampled image: `factor` sub-pixels per pixel side, with pixel
// (u, v) covering sub-pixels factor*u ... factor*u + factor - 1 (so its centre is
// sub-pixel factor*u + (factor-1)/2 when the factor is odd).
PinholeCamera Supersampled(const PinholeCamera& c, int factor) {
  PinholeCamera s = c;
  s.width = c.width * factor;
  s.height = c.height * factor;
  s.fx = c.fx * factor;
  s.fy = c.fy * factor;
  s.cx = (c.cx + 0.5) * factor - 0.5;
  s.cy = (c.cy + 0.5) * factor - 0.5;
  s.distortion.clear();
  return s;
}

// A box of uniform colour (flat 2x2 textures on the six faces).
Mesh MakeColoredBox(const Eigen::Vector3d& size_m, const Eigen::Vector3d& color_bgr) {
  std::array<cv::Mat, 6> textures;
  for (auto& t : textures) {
    t = cv::Mat(2, 2, CV_32FC3, cv::Scalar(color_bgr[0], color_bgr[1], color_bgr[2]));
  }
  return MakeTexturedBox(size_m, textures);
}

// The rectangle [x0, x1] x [y0, y1] on the plane z = distance (world frame) that covers
// every camera's view with a 15 % margin, widened to the aspect ratio `aspect` (w / h).
void BackgroundExtent(const Rig& rig, double distance, double aspect, Eigen::Vector2d* lo,
                      Eigen::Vector2d* hi) {
  *lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  *hi = -*lo;
  for (const RigCamera& cam : rig.cameras) {
    const PinholeCamera& k = cam.intrinsics;
    const Eigen::Vector3d centre = cam.world_from_cam.translation();
    const double corners[4][2] = {{-0.5, -0.5},
                                  {k.width - 0.5, -0.5},
                                  {k.width - 0.5, k.height - 0.5},
                                  {-0.5, k.height - 0.5}};
    for (const auto& c : corners) {
      const Eigen::Vector3d dir =
          cam.world_from_cam.rotation() * k.Unproject(Eigen::Vector2d(c[0], c[1]), 1.0);
      UNSEEN_CHECK(dir.z() > 1e-3 && distance > centre.z(),
                   "camera {} does not look at the background plane z = {} m (it must look "
                   "along +z, towards the scene)",
                   cam.name, distance);
      const Eigen::Vector3d p = centre + dir * ((distance - centre.z()) / dir.z());
      *lo = lo->cwiseMin(p.head<2>());
      *hi = hi->cwiseMax(p.head<2>());
    }
  }
  const Eigen::Vector2d size = (*hi - *lo) * 1.15;
  const Eigen::Vector2d mid = 0.5 * (*hi + *lo);
  Eigen::Vector2d half = 0.5 * size;
  if (size.x() / size.y() > aspect) {
    half.y() = half.x() / aspect;
  } else {
    half.x() = half.y() * aspect;
  }
  *lo = mid - half;
  *hi = mid + half;
}

// A quad on z = distance facing the cameras, in the world frame (object frame = world),
// textured by `texture` (or of uniform `color_bgr` when the texture is empty).
Mesh MakeBackgroundMesh(const Rig& rig, const BackgroundSpec& spec, const cv::Mat& texture) {
  const double aspect = texture.empty() ? 2.0 : static_cast<double>(texture.cols) / texture.rows;
  Eigen::Vector2d lo, hi;
  BackgroundExtent(rig, spec.distance_m, aspect, &lo, &hi);
  Mesh m;
  const float z = static_cast<float>(spec.distance_m);
  m.vertices = {{float(lo.x()), float(lo.y()), z},
                {float(hi.x()), float(lo.y()), z},
                {float(hi.x()), float(hi.y()), z},
                {float(lo.x()), float(hi.y()), z}};
  // Facing -z (towards the cameras): counter-clockwise seen from there.
  m.triangles = {{0, 2, 1}, {0, 3, 2}};
  m.normals.assign(4, Eigen::Vector3f(0, 0, -1));
  Material mat;
  mat.name = "background";
  if (texture.empty()) {
    const Eigen::Vector3d c = spec.color_bgr * spec.brightness;
    mat.diffuse_bgr = c.cast<float>();
    m.colors_bgr.assign(4, c.cast<float>());
  } else {
    // Image top (world y smallest, y is down) at v = 1 (OBJ convention).
    m.uvs = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
    mat.texture = texture * spec.brightness;
  }
  m.materials.push_back(mat);
  m.triangle_materials.assign(2, 0);
  m.Check("background plane");
  return m;
}

// The scene's lights in the frame of one camera at time t (render/shading.h wants them
// there). A point light's intensity is given at its reference distance; shading.h's at 1 m.
Lighting LightsInCamera(const LightingSpec& spec, const Rigid3d& cam_from_world, double t_s) {
  Lighting out;
  out.ambient_bgr = Eigen::Vector3f::Constant(static_cast<float>(spec.ambient));
  for (const LightSpec& l : spec.lights) {
    if (l.type == LightSpec::Type::kPoint) {
      PointLight p;
      p.position_in_cam = cam_from_world * l.PositionAt(t_s);
      p.color_bgr = l.color_bgr.cast<float>();
      p.intensity = l.intensity * l.reference_distance_m * l.reference_distance_m;
      p.cast_shadows = l.cast_shadows;
      out.point.push_back(p);
    } else {
      DirectionalLight d;
      d.direction_in_cam = cam_from_world.rotation() * l.direction;
      d.color_bgr = l.color_bgr.cast<float>();
      d.intensity = l.intensity;
      d.cast_shadows = l.cast_shadows;
      out.directional.push_back(d);
    }
  }
  return out;
}

// The object-space bounding sphere of `mesh`.
struct Sphere {
  Eigen::Vector3d centre;
  double radius;
};
Sphere BoundingSphereOf(const Mesh& mesh) {
  Eigen::Vector3f c;
  float r = 0.0f;
  mesh.BoundingSphere(&c, &r);
  return {c.cast<double>(), static_cast<double>(r)};
}

// Adds fixed-size blobs of missing depth (value 0) until `fraction` of the valid pixels
// are dropped, the way structured-light sensors lose patches.
void DropDepthHoles(double fraction, std::mt19937& rng, cv::Mat* depth) {
  const int valid = cv::countNonZero(*depth);
  const int target = static_cast<int>(std::lround(fraction * valid));
  if (target <= 0) return;
  std::uniform_int_distribution<int> ux(0, depth->cols - 1), uy(0, depth->rows - 1);
  std::uniform_int_distribution<int> ur(0, 2);
  int dropped = 0;
  for (int attempts = 0; dropped < target && attempts < 100 * target + 1000; ++attempts) {
    const int cx = ux(rng), cy = uy(rng), r = ur(rng);
    for (int y = std::max(0, cy - r); y <= std::min(depth->rows - 1, cy + r) && dropped < target;
         ++y) {
      float* row = depth->ptr<float>(y);
      for (int x = std::max(0, cx - r); x <= std::min(depth->cols - 1, cx + r) && dropped < target;
           ++x) {
        if ((x - cx) * (x - cx) + (y - cy) * (y - cy) > r * r + r) continue;
        if (row[x] > 0.0f) {
          row[x] = 0.0f;
          ++dropped;
        }
      }
    }
  }
}

// Layer ids in the composited id buffer.
constexpr uint8_t kIdBackground = 1;
constexpr uint8_t kIdObject = 2;
constexpr uint8_t kIdFirstOccluder = 3;

// Writes the covered pixels of `b` that are nearer than the current surface into the
// full-image composite (colour, depth, id).
void Composite(const RenderBuffers& b, uint8_t id, cv::Mat* color, cv::Mat* depth, cv::Mat* ids) {
  if (b.roi.empty()) return;
  for (int y = 0; y < b.mask.rows; ++y) {
    const uint8_t* m = b.mask.ptr<uint8_t>(y);
    const float* z = b.depth.ptr<float>(y);
    const cv::Vec3f* c = b.color.ptr<cv::Vec3f>(y);
    float* dz = depth->ptr<float>(y + b.roi.y0) + b.roi.x0;
    cv::Vec3f* dc = color->ptr<cv::Vec3f>(y + b.roi.y0) + b.roi.x0;
    uint8_t* di = ids->ptr<uint8_t>(y + b.roi.y0) + b.roi.x0;
    for (int x = 0; x < b.mask.cols; ++x) {
      if (m[x] && (dz[x] == 0.0f || z[x] < dz[x])) {
        dz[x] = z[x];
        dc[x] = c[x];
        di[x] = id;
      }
    }
  }
}

}  // namespace

Synthesizer::Synthesizer(Scene scene) : scene_(std::move(scene)) {
  scene_.Check();
  num_frames_ = scene_.NumFrames();
  object_mesh_ = BuildObjectMesh(scene_.object);

  cv::Mat texture;
  switch (scene_.background.type) {
    case BackgroundSpec::Type::kColor:
      break;
    case BackgroundSpec::Type::kImage:
      texture = LoadColorImage(scene_.background.image_path);
      break;
    case BackgroundSpec::Type::kClutter:
      texture = MakeClutterImage(scene_.background.clutter_width_px,
                                 scene_.background.clutter_height_px, scene_.seed);
      break;
  }
  background_mesh_ = MakeBackgroundMesh(scene_.rig, scene_.background, texture);
  // The background and the cameras do not move: render it once per camera.
  RenderOptions flat;
  flat.cull_back_faces = false;
  RenderBuffers buffers;
  for (const RigCamera& cam : scene_.rig.cameras) {
    const PinholeCamera ss = Supersampled(cam.intrinsics, scene_.sensor.antialias);
    Render(background_mesh_, ss, cam.cam_from_world(), ss.ImageRect(), flat, &buffers);
    background_color_.push_back(buffers.color.clone());
    background_depth_.push_back(buffers.depth.clone());
  }

  const double duration_s = (num_frames_ - 1) / scene_.fps;
  for (size_t i = 0; i < scene_.occluders.size(); ++i) {
    const OccluderSpec& o = scene_.occluders[i];
    if (o.type == OccluderSpec::Type::kBar) {
      occluder_meshes_.push_back(MakeColoredBox(o.size_m, o.color_bgr));
      WaypointTrajectoryOptions t;
      t.origin_m = o.start_m;
      t.waypoints_m = {Eigen::Vector3d::Zero(), o.end_m - o.start_m};
      t.start_time_s = o.start_time_s;
      const double length = (o.end_m - o.start_m).norm();
      // Speed 0: sweep from start to end over the sequence (from start_time_s).
      const double sweep_s = duration_s - o.start_time_s;
      t.speed_m_s = o.speed_m_s > 0.0                 ? o.speed_m_s
                    : (length > 0.0 && sweep_s > 0.0) ? length / sweep_s
                                                      : 1.0;
      occluder_trajectories_.push_back(std::make_shared<WaypointTrajectory>(t));
    } else {
      occluder_meshes_.push_back(BuildObjectMesh(o.object));
      occluder_trajectories_.push_back(o.trajectory);
    }
  }
}

SynthFrame Synthesizer::RenderFrame(int frame_id) const {
  UNSEEN_CHECK(frame_id >= 0, "frame id {} must not be negative", frame_id);
  SynthFrame out;
  out.frame_id = frame_id;
  out.time_s = frame_id / scene_.fps;
  out.world_from_obj = scene_.trajectory->WorldFromObj(out.time_s);
  const int n = scene_.rig.size();
  out.images.resize(n);
  out.clean_depths.resize(n);
  out.masks.resize(n);
  if (scene_.depth.enabled) out.depths.resize(n);
  // Cameras in parallel (each writes only its own slots; randomness is per camera).
  std::vector<std::exception_ptr> errors(n);
#pragma omp parallel for schedule(dynamic) if (n > 1)
  for (int c = 0; c < n; ++c) {
    try {
      RenderCamera(c, frame_id, &out);
    } catch (...) {
      errors[c] = std::current_exception();
    }
  }
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  return out;
}

void Synthesizer::RenderCamera(int camera, int frame_id, SynthFrame* out) const {
  const RigCamera& rig_cam = scene_.rig.cameras[camera];
  const int factor = scene_.sensor.antialias;
  const PinholeCamera ss = Supersampled(rig_cam.intrinsics, factor);
  const Rigid3d cam_from_world = rig_cam.cam_from_world();
  const double t = out->time_s;
  const Lighting lighting = LightsInCamera(scene_.lighting, cam_from_world, t);
  const ShadingOptions shading;

  // Start from the background (unlit: a photo or a wall as it appears).
  cv::Mat color = background_color_[camera].clone();
  cv::Mat depth = background_depth_[camera].clone();
  cv::Mat ids(ss.height, ss.width, CV_8UC1, cv::Scalar(kIdBackground));

  RenderOptions flat;
  flat.cull_back_faces = false;
  RenderOptions shaded = flat;
  shaded.cull_back_faces = true;
  RenderBuffers buffers;

  // A mesh at a pose, restricted to the rectangle of its bounding sphere.
  auto render_mesh = [&](const Mesh& mesh, const Rigid3d& cam_from_obj, bool lit, uint8_t id) {
    const Sphere sphere = BoundingSphereOf(mesh);
    const auto rect = ss.SphereRect(cam_from_obj * sphere.centre, sphere.radius);
    if (!rect) return;
    const PixelRect roi = rect->Grow(2).Intersect(ss.ImageRect());
    if (lit) {
      RenderShaded(mesh, ss, cam_from_obj, roi, lighting, shaded, shading, &buffers);
    } else {
      Render(mesh, ss, cam_from_obj, roi, flat, &buffers);
    }
    Composite(buffers, id, &color, &depth, &ids);
  };

  render_mesh(object_mesh_, cam_from_world * out->world_from_obj, true, kIdObject);
  for (size_t i = 0; i < occluder_meshes_.size(); ++i) {
    const OccluderSpec& o = scene_.occluders[i];
    const bool lit = o.type == OccluderSpec::Type::kObject || o.shaded;
    render_mesh(occluder_meshes_[i], cam_from_world * occluder_trajectories_[i]->WorldFromObj(t),
                lit, static_cast<uint8_t>(kIdFirstOccluder + i));
  }

  // Down to the camera's resolution: colour by area averaging, depth and mask at the centre
  // sub-sample (the pixel centre).
  const PinholeCamera& k = rig_cam.intrinsics;
  cv::Mat image;
  if (factor == 1) {
    image = color;
  } else {
    cv::resize(color, image, cv::Size(k.width, k.height), 0, 0, cv::INTER_AREA);
  }
  cv::Mat clean_depth(k.height, k.width, CV_32FC1);
  cv::Mat mask(k.height, k.width, CV_8UC1);
  const int off = (factor - 1) / 2;
  for (int v = 0; v < k.height; ++v) {
    const float* dz = depth.ptr<float>(v * factor + off);
    const uint8_t* di = ids.ptr<uint8_t>(v * factor + off);
    float* oz = clean_depth.ptr<float>(v);
    uint8_t* om = mask.ptr<uint8_t>(v);
    for (int u = 0; u < k.width; ++u) {
      oz[u] = dz[u * factor + off];
      om[u] = di[u * factor + off] == kIdObject ? 255 : 0;
    }
  }

  // Sensor: defocus blur, gain, additive noise, clipping.
  const SensorSpec& sensor = scene_.sensor;
  if (sensor.blur_sigma_px > 0.0) {
    cv::GaussianBlur(image, image, cv::Size(0, 0), sensor.blur_sigma_px, sensor.blur_sigma_px,
                     cv::BORDER_REFLECT);
  }
  if (sensor.gain != 1.0) image *= sensor.gain;
  if (sensor.noise_sigma > 0.0) {
    std::mt19937 rng = MakeRng(scene_.seed, frame_id, camera, Stream::kImageNoise);
    std::normal_distribution<float> noise(0.0f, static_cast<float>(sensor.noise_sigma / 255.0));
    for (int v = 0; v < image.rows; ++v) {
      float* row = image.ptr<float>(v);
      for (int i = 0; i < image.cols * 3; ++i) row[i] += noise(rng);
    }
  }
  cv::min(cv::max(image, 0.0), 1.0, image);
  out->images[camera] = image;
  out->clean_depths[camera] = clean_depth;
  out->masks[camera] = mask;

  if (scene_.depth.enabled) {
    cv::Mat d = clean_depth.clone();
    if (scene_.depth.noise_sigma_mm > 0.0) {
      std::mt19937 rng = MakeRng(scene_.seed, frame_id, camera, Stream::kDepthNoise);
      std::normal_distribution<float> noise(0.0f,
                                            static_cast<float>(scene_.depth.noise_sigma_mm * 1e-3));
      for (int v = 0; v < d.rows; ++v) {
        float* row = d.ptr<float>(v);
        for (int u = 0; u < d.cols; ++u) {
          if (row[u] > 0.0f) row[u] = std::max(1e-4f, row[u] + noise(rng));
        }
      }
    }
    if (scene_.depth.hole_fraction > 0.0) {
      std::mt19937 rng = MakeRng(scene_.seed, frame_id, camera, Stream::kDepthHoles);
      DropDepthHoles(scene_.depth.hole_fraction, rng, &d);
    }
    out->depths[camera] = d;
  }
}

void SynthOptions::Check() const {
  UNSEEN_CHECK(max_frames == -1 || max_frames > 0,
               "SynthOptions: max_frames {} must be positive (or -1 = all)", max_frames);
}

SynthSummary Synthesize(const Scene& scene_in, const std::string& out_dir,
                        const SynthOptions& options) {
  options.Check();
  Scene scene = scene_in;
  if (options.seed) scene.seed = *options.seed;
  if (options.force_depth) scene.depth.enabled = true;
  const Timer timer;
  const Synthesizer synth(scene);
  const int frames = options.max_frames > 0 ? std::min(options.max_frames, synth.num_frames())
                                            : synth.num_frames();

  SequenceWriterOptions w;
  w.fps = scene.fps;
  w.image_extension = "." + scene.sensor.image_format;
  w.jpeg_quality = scene.sensor.jpeg_quality;
  w.depth_scale = scene.depth.depth_scale_mm;
  w.reference_camera = scene.reference_camera;
  w.notes =
      fmt::format("{}: {} [rendered by unseen synth from {}, seed {}]", scene.name, scene.notes,
                  std::filesystem::path(scene.path).filename().string(), scene.seed);
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  UNSEEN_CHECK(!ec, "output folder {} cannot be created: {}", out_dir, ec.message());
  SequenceWriter writer(out_dir, scene.rig, w);
  Mesh model = synth.object_mesh();
  if (scene.model_scale != 1.0) model.Scale(static_cast<float>(scene.model_scale));
  writer.WriteModel(model);

  UNSEEN_LOG_INFO("synth: {} -> {}: {} frames x {} cameras ({}x{} px, antialias {}x)", scene.path,
                  out_dir, frames, scene.rig.size(), scene.rig.cameras[0].intrinsics.width,
                  scene.rig.cameras[0].intrinsics.height, scene.sensor.antialias);
  ProgressLine progress("synth", frames, options.progress);
  for (int k = 0; k < frames; ++k) {
    const SynthFrame f = synth.RenderFrame(k);
    writer.WriteFrame(k, f.images, scene.depth.enabled ? f.depths : std::vector<cv::Mat>{},
                      f.world_from_obj, scene.write_masks ? f.masks : std::vector<cv::Mat>{});
    progress.Update(k + 1);
  }
  writer.Finish();
  progress.Finish();

  SynthSummary summary;
  summary.frames = frames;
  summary.cameras = scene.rig.size();
  summary.seconds = timer.ElapsedSeconds();
  summary.seconds_per_frame = frames > 0 ? summary.seconds / frames : 0.0;
  UNSEEN_LOG_INFO("synth: wrote {} frames in {:.1f} s ({:.3f} s per frame)", frames,
                  summary.seconds, summary.seconds_per_frame);
  return summary;
}

}  // namespace unseen
