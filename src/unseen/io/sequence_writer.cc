// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// SequenceWriter: writes the DATASET.md layout (one BOP scene per camera + sequence.json).

#include <cmath>
#include <filesystem>
#include <set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "unseen/io/bop_json.h"
#include "unseen/io/sequence.h"
#include "unseen/mesh/mesh_io.h"
#include "unseen/util/error.h"
#include "unseen/util/files.h"
#include "unseen/util/logging.h"

namespace unseen {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Vertices beyond which the model diameter is computed from extreme points only.
constexpr int kExactDiameterMaxVertices = 4000;

// Largest distance between two vertices (the BOP "diameter"), in the mesh's units. Exact
// for small meshes; for large ones the maximum over the extreme vertices along 2000
// directions spread over the sphere (the diametral pair is extreme along its own
// direction, so this misses the true value only by the angular spacing's second order).
double Diameter(const std::vector<Eigen::Vector3f>& vertices) {
  std::vector<Eigen::Vector3d> candidates;
  if (static_cast<int>(vertices.size()) <= kExactDiameterMaxVertices) {
    for (const Eigen::Vector3f& v : vertices) candidates.push_back(v.cast<double>());
  } else {
    constexpr int kDirections = 2000;
    std::set<size_t> extreme;
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < kDirections; ++i) {  // Fibonacci sphere
      const double z = 1.0 - 2.0 * (i + 0.5) / kDirections;
      const double r = std::sqrt(1.0 - z * z);
      const Eigen::Vector3f d(r * std::cos(golden * i), r * std::sin(golden * i), z);
      size_t best = 0;
      float best_dot = -std::numeric_limits<float>::infinity();
      for (size_t k = 0; k < vertices.size(); ++k) {
        const float dot = d.dot(vertices[k]);
        if (dot > best_dot) {
          best_dot = dot;
          best = k;
        }
      }
      extreme.insert(best);
    }
    for (size_t k : extreme) candidates.push_back(vertices[k].cast<double>());
  }
  double best = 0.0;
  for (size_t i = 0; i < candidates.size(); ++i) {
    for (size_t j = i + 1; j < candidates.size(); ++j) {
      best = std::max(best, (candidates[i] - candidates[j]).squaredNorm());
    }
  }
  return std::sqrt(best);
}

// An 8-bit BGR copy of a CV_32FC3 [0, 1] or CV_8UC3 image.
cv::Mat To8Bit(const cv::Mat& image, const std::string& what) {
  UNSEEN_CHECK(image.type() == CV_32FC3 || image.type() == CV_8UC3,
               "{}: image must be CV_32FC3 [0,1] or CV_8UC3 (OpenCV type {})", what, image.type());
  if (image.type() == CV_8UC3) return image;
  cv::Mat out;
  image.convertTo(out, CV_8U, 255.0);  // rounds and saturates
  return out;
}

}  // namespace

void SequenceWriterOptions::Check() const {
  UNSEEN_CHECK(std::isfinite(fps) && fps > 0.0, "SequenceWriterOptions: fps {} must be positive",
               fps);
  UNSEEN_CHECK(obj_id > 0, "SequenceWriterOptions: obj_id {} must be positive", obj_id);
  UNSEEN_CHECK(image_extension == ".png" || image_extension == ".jpg",
               "SequenceWriterOptions: image_extension \"{}\" must be \".png\" or \".jpg\"",
               image_extension);
  UNSEEN_CHECK(jpeg_quality >= 1 && jpeg_quality <= 100,
               "SequenceWriterOptions: jpeg_quality {} must be in [1, 100]", jpeg_quality);
  UNSEEN_CHECK(std::isfinite(depth_scale) && depth_scale > 0.0,
               "SequenceWriterOptions: depth_scale {} must be positive", depth_scale);
  UNSEEN_CHECK(reference_camera >= 0, "SequenceWriterOptions: reference_camera {} must be >= 0",
               reference_camera);
}

struct SequenceWriter::Impl {
  fs::path dir;
  Rig rig;
  SequenceWriterOptions options;
  std::vector<nlohmann::ordered_json> scene_camera;  // per camera, frames in written order
  std::vector<nlohmann::ordered_json> scene_gt;      // per camera
  std::set<int> frames_written;
  bool any_gt = false;
  std::string model_file;  // relative to dir, once written
  bool finished = false;
  bool warned_depth_range = false;

  fs::path CameraDir(int c) const { return dir / rig.cameras[c].name; }
};

SequenceWriter::SequenceWriter(const std::string& dir, const Rig& rig,
                               const SequenceWriterOptions& options)
    : impl_(std::make_unique<Impl>()) {
  options.Check();
  rig.Check();
  UNSEEN_CHECK(rig.size() > 0, "{}: the rig has no cameras", dir);
  UNSEEN_CHECK(options.reference_camera < rig.size(),
               "{}: reference_camera {} out of range for a rig of {} cameras", dir,
               options.reference_camera, rig.size());
  std::set<std::string> names;
  for (const RigCamera& camera : rig.cameras) {
    UNSEEN_CHECK(!camera.name.empty() && camera.name.find('/') == std::string::npos &&
                     camera.name != "." && camera.name != ".." && camera.name != "models",
                 "{}: camera name \"{}\" cannot be a folder name", dir, camera.name);
    UNSEEN_CHECK(names.insert(camera.name).second, "{}: camera name \"{}\" used twice", dir,
                 camera.name);
    camera.intrinsics.Check(fmt::format("{}: camera {}", dir, camera.name));
    UNSEEN_CHECK(camera.world_from_cam.IsValid(), "{}: camera {} has an invalid pose {}", dir,
                 camera.name, camera.world_from_cam.ToString());
  }
  impl_->dir = dir;
  impl_->rig = rig;
  impl_->options = options;
  impl_->scene_camera.assign(rig.size(), nlohmann::ordered_json::object());
  impl_->scene_gt.assign(rig.size(), nlohmann::ordered_json::object());
  std::error_code ec;
  for (int c = 0; c < rig.size(); ++c) {
    fs::create_directories(impl_->CameraDir(c) / "rgb", ec);
    UNSEEN_CHECK(!ec, "{}: cannot create folder: {}", (impl_->CameraDir(c) / "rgb").string(),
                 ec.message());
  }
}

SequenceWriter::~SequenceWriter() {
  if (!impl_ || impl_->finished) return;
  try {
    Finish();
  } catch (const std::exception& e) {
    UNSEEN_LOG_ERROR("{}", e.what());
  }
}

void SequenceWriter::WriteModel(const Mesh& mesh_in_metres) {
  mesh_in_metres.Check("SequenceWriter::WriteModel mesh");
  const fs::path models = impl_->dir / "models";
  std::error_code ec;
  fs::create_directories(models, ec);
  UNSEEN_CHECK(!ec, "{}: cannot create folder: {}", models.string(), ec.message());
  const std::string name = fmt::format("obj_{:06d}.ply", impl_->options.obj_id);
  SaveMesh(mesh_in_metres, (models / name).string(), 1000.0);
  impl_->model_file = "models/" + name;

  Eigen::Vector3f min, max;
  mesh_in_metres.BoundingBox(&min, &max);
  const Eigen::Vector3d min_mm = min.cast<double>() * 1e3;
  const Eigen::Vector3d size_mm = (max - min).cast<double>() * 1e3;
  json info = json::object();
  info[std::to_string(impl_->options.obj_id)] = {
      {"diameter", Diameter(mesh_in_metres.vertices) * 1e3},
      {"min_x", min_mm.x()},
      {"min_y", min_mm.y()},
      {"min_z", min_mm.z()},
      {"size_x", size_mm.x()},
      {"size_y", size_mm.y()},
      {"size_z", size_mm.z()}};
  bop::WriteJsonFile((models / "models_info.json").string(), info);
}

void SequenceWriter::WriteFrame(int frame_id, const std::vector<cv::Mat>& images,
                                const std::vector<cv::Mat>& depths_m,
                                const std::optional<Rigid3d>& world_from_obj,
                                const std::vector<cv::Mat>& masks) {
  Impl& w = *impl_;
  const std::string where = fmt::format("{} frame {}", w.dir.string(), frame_id);
  UNSEEN_CHECK(!w.finished, "{}: the writer is finished", where);
  UNSEEN_CHECK(frame_id >= 0, "{}: frame id must be non-negative", where);
  UNSEEN_CHECK(!w.frames_written.count(frame_id), "{}: frame written twice", where);
  const int n = w.rig.size();
  UNSEEN_CHECK(static_cast<int>(images.size()) == n, "{}: {} images for a rig of {} cameras", where,
               images.size(), n);
  UNSEEN_CHECK(depths_m.empty() || static_cast<int>(depths_m.size()) == n,
               "{}: {} depth images for a rig of {} cameras", where, depths_m.size(), n);
  UNSEEN_CHECK(masks.empty() || static_cast<int>(masks.size()) == n,
               "{}: {} masks for a rig of {} cameras", where, masks.size(), n);
  if (world_from_obj) {
    UNSEEN_CHECK(world_from_obj->IsValid(), "{}: invalid world_from_obj {}", where,
                 world_from_obj->ToString());
  }
  // Check everything before writing anything.
  for (int c = 0; c < n; ++c) {
    const PinholeCamera& k = w.rig.cameras[c].intrinsics;
    const std::string what = fmt::format("{} camera {}", where, w.rig.cameras[c].name);
    auto check_size = [&](const cv::Mat& m, const char* kind) {
      UNSEEN_CHECK(m.cols == k.width && m.rows == k.height, "{}: {} is {}x{}, camera is {}x{}",
                   what, kind, m.cols, m.rows, k.width, k.height);
    };
    UNSEEN_CHECK(!images[c].empty(), "{}: image is empty", what);
    check_size(images[c], "image");
    if (!depths_m.empty() && !depths_m[c].empty()) {
      UNSEEN_CHECK(depths_m[c].type() == CV_32FC1, "{}: depth must be CV_32FC1 metres", what);
      check_size(depths_m[c], "depth");
    }
    if (!masks.empty() && !masks[c].empty()) {
      UNSEEN_CHECK(masks[c].type() == CV_8UC1, "{}: mask must be CV_8UC1", what);
      check_size(masks[c], "mask");
    }
  }

  const std::string stem = bop::FrameName(frame_id);
  const double depth_scale = w.options.depth_scale;
  for (int c = 0; c < n; ++c) {
    const RigCamera& camera = w.rig.cameras[c];
    const fs::path cam_dir = w.CameraDir(c);
    const std::string what = fmt::format("{} camera {}", where, camera.name);
    const std::string image_file = (cam_dir / "rgb" / (stem + w.options.image_extension)).string();
    std::vector<int> params;
    if (w.options.image_extension == ".jpg") {
      params = {cv::IMWRITE_JPEG_QUALITY, w.options.jpeg_quality};
    }
    UNSEEN_CHECK(cv::imwrite(image_file, To8Bit(images[c], what), params),
                 "{}: could not write image", image_file);

    if (!depths_m.empty() && !depths_m[c].empty()) {
      std::error_code ec;
      fs::create_directories(cam_dir / "depth", ec);
      UNSEEN_CHECK(!ec, "{}: cannot create folder: {}", (cam_dir / "depth").string(), ec.message());
      cv::Mat depth16(depths_m[c].size(), CV_16UC1);
      for (int y = 0; y < depth16.rows; ++y) {
        const float* in = depths_m[c].ptr<float>(y);
        uint16_t* out = depth16.ptr<uint16_t>(y);
        for (int x = 0; x < depth16.cols; ++x) {
          const double value = std::round(in[x] * 1e3 / depth_scale);
          if (!(value > 0.0)) {
            out[x] = 0;  // no measurement (0, negative or NaN)
          } else if (value > 65535.0) {
            out[x] = 0;  // out of range, as a sensor reports it
            if (!w.warned_depth_range) {
              UNSEEN_LOG_WARN(
                  "{}: depth {} m exceeds the 16-bit range at depth_scale {}; "
                  "written as 0 (no measurement)",
                  what, in[x], depth_scale);
              w.warned_depth_range = true;
            }
          } else {
            out[x] = static_cast<uint16_t>(value);
          }
        }
      }
      const std::string depth_file = (cam_dir / "depth" / (stem + ".png")).string();
      UNSEEN_CHECK(cv::imwrite(depth_file, depth16), "{}: could not write depth", depth_file);
    }
    if (!masks.empty() && !masks[c].empty()) {
      std::error_code ec;
      fs::create_directories(cam_dir / "mask_visib", ec);
      UNSEEN_CHECK(!ec, "{}: cannot create folder: {}", (cam_dir / "mask_visib").string(),
                   ec.message());
      const std::string mask_file = (cam_dir / "mask_visib" / (stem + "_000000.png")).string();
      UNSEEN_CHECK(cv::imwrite(mask_file, masks[c]), "{}: could not write mask", mask_file);
    }

    const PinholeCamera& k = camera.intrinsics;
    json entry = {{"cam_K", {k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0}},
                  {"depth_scale", depth_scale}};
    bop::SetPoseMm(camera.cam_from_world(), "cam_R_w2c", "cam_t_w2c", &entry);
    if (!k.distortion.empty()) entry["dist"] = k.distortion;
    w.scene_camera[c][std::to_string(frame_id)] = entry;
    if (world_from_obj) {
      json gt = {{"obj_id", w.options.obj_id}};
      bop::SetPoseMm(camera.cam_from_world() * *world_from_obj, "cam_R_m2c", "cam_t_m2c", &gt);
      w.scene_gt[c][std::to_string(frame_id)] = nlohmann::ordered_json::array({gt});
    }
  }
  if (world_from_obj) w.any_gt = true;
  w.frames_written.insert(frame_id);
}

void SequenceWriter::Finish() {
  Impl& w = *impl_;
  if (w.finished) return;
  w.finished = true;
  json cameras = json::array();
  for (int c = 0; c < w.rig.size(); ++c) {
    const fs::path cam_dir = w.CameraDir(c);
    // A camera with depth needs a depth image for every frame: frames written without one
    // get an all-zero image (no measurement).
    if (IsFolder(cam_dir / "depth")) {
      const PinholeCamera& k = w.rig.cameras[c].intrinsics;
      const cv::Mat none(k.height, k.width, CV_16UC1, cv::Scalar(0));
      for (int frame_id : w.frames_written) {
        const fs::path file = cam_dir / "depth" / (bop::FrameName(frame_id) + ".png");
        if (Exists(file)) continue;
        UNSEEN_CHECK(cv::imwrite(file.string(), none), "{}: could not write depth", file.string());
      }
    }
    bop::WriteJsonFile((cam_dir / "scene_camera.json").string(), w.scene_camera[c]);
    if (w.any_gt) bop::WriteJsonFile((cam_dir / "scene_gt.json").string(), w.scene_gt[c]);
    cameras.push_back(w.rig.cameras[c].name);
  }
  json object = {{"obj_id", w.options.obj_id}};
  if (!w.model_file.empty()) object["model"] = w.model_file;
  nlohmann::ordered_json sequence = {
      {"fps", w.options.fps},
      {"cameras", cameras},
      {"reference_camera", w.rig.cameras[w.options.reference_camera].name},
      {"object", object},
      {"frames", w.frames_written.size()}};
  if (!w.options.notes.empty()) sequence["notes"] = w.options.notes;
  bop::WriteJsonFile((w.dir / "sequence.json").string(), sequence);
}

}  // namespace unseen
