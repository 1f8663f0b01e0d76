// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/io/sequence.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "unseen/image/image_io.h"
#include "unseen/io/bop_json.h"
#include "unseen/mesh/mesh_io.h"
#include "unseen/util/error.h"
#include "unseen/util/files.h"
#include "unseen/util/logging.h"

namespace unseen {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

enum class Kind { kBop, kVideo, kImageFolder };

// Tolerances for "the same value in every frame" of scene_camera.json.
constexpr double kIntrinsicsTolerance = 1e-9;  // relative, cam_K / dist
constexpr double kExtrinsicsToleranceM = 1e-6;
constexpr double kExtrinsicsToleranceRad = 1e-6;

// One camera as stored: its files per frame, calibration and ground truth.
struct CameraSource {
  std::string name;
  std::string dir;           // BOP scene folder; empty for video/image folders
  PinholeCamera intrinsics;  // as calibrated, with distortion
  Rigid3d world_from_cam;
  std::vector<std::string> image_paths;  // per frame index
  std::vector<std::string> depth_paths;  // per frame index, or empty (no depth)
  std::vector<double> depth_scales;      // per frame index: PNG value x scale = mm
  bool has_gt = false;
  std::vector<std::optional<Rigid3d>> cam_from_obj;  // per frame index when has_gt
  cv::Mat map_x, map_y;                              // undistortion maps (empty without distortion)

  // Computes the undistortion maps when the camera has distortion. The undistorted image
  // keeps the same K (cv::initUndistortRectifyMap with newCameraMatrix = K), so pixels
  // near the border that map outside the source image become black (depth 0).
  void PrepareUndistortion() {
    if (!intrinsics.HasDistortion()) return;
    cv::Mat k = (cv::Mat_<double>(3, 3) << intrinsics.fx, 0.0, intrinsics.cx, 0.0, intrinsics.fy,
                 intrinsics.cy, 0.0, 0.0, 1.0);
    cv::initUndistortRectifyMap(k, intrinsics.distortion, cv::noArray(), k,
                                cv::Size(intrinsics.width, intrinsics.height), CV_32FC1, map_x,
                                map_y);
  }
  cv::Mat Undistort(const cv::Mat& image, int interpolation) const {
    if (map_x.empty()) return image;
    cv::Mat out;
    cv::remap(image, out, map_x, map_y, interpolation, cv::BORDER_CONSTANT, cv::Scalar::all(0));
    return out;
  }
  // Throws naming `file` when `image` does not have this camera's size.
  void CheckSize(const cv::Mat& image, const std::string& file) const {
    UNSEEN_CHECK(image.cols == intrinsics.width && image.rows == intrinsics.height,
                 "{}: image is {}x{} but camera {} is {}x{}", file, image.cols, image.rows, name,
                 intrinsics.width, intrinsics.height);
  }
};

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// Files in `dir` whose stem is a frame number and whose extension is in `extensions`
// (lower case), keyed by that number. Two files for one number: the first extension wins.
std::map<int, std::string> ListFrameFiles(const fs::path& dir,
                                          const std::vector<std::string>& extensions) {
  std::map<int, std::string> files;
  std::map<int, size_t> rank;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    const std::string ext = Lower(entry.path().extension().string());
    const auto it = std::find(extensions.begin(), extensions.end(), ext);
    if (it == extensions.end()) continue;
    const std::string stem = entry.path().stem().string();
    const auto is_digit = [](unsigned char c) { return std::isdigit(c) != 0; };
    if (stem.empty() || !std::all_of(stem.begin(), stem.end(), is_digit) || stem.size() > 9) {
      continue;
    }
    const int id = std::stoi(stem);
    const size_t r = static_cast<size_t>(it - extensions.begin());
    if (!rank.count(id) || r < rank[id]) {
      rank[id] = r;
      files[id] = entry.path().string();
    }
  }
  return files;
}

bool NearlyEqual(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::abs(a[i] - b[i]) > kIntrinsicsTolerance * std::max(1.0, std::abs(a[i]))) {
      return false;
    }
  }
  return true;
}

// Reads cam_K (+ "dist") of one scene_camera.json entry as a camera without image size.
PinholeCamera ParseIntrinsics(const json& entry, const std::string& what) {
  const std::vector<double> k = bop::GetNumbers(entry, "cam_K", 9, what);
  UNSEEN_CHECK(k[1] == 0.0 && k[3] == 0.0 && k[6] == 0.0 && k[7] == 0.0 && k[8] == 1.0,
               "{}: field \"cam_K\" = [{}] is not a pinhole matrix [fx 0 cx 0 fy cy 0 0 1] "
               "(skew and a last row other than [0 0 1] are not supported)",
               what, fmt::join(k, ", "));
  PinholeCamera camera;
  camera.fx = k[0];
  camera.cx = k[2];
  camera.fy = k[4];
  camera.cy = k[5];
  UNSEEN_CHECK(camera.fx > 0.0 && camera.fy > 0.0,
               "{}: field \"cam_K\" has focal lengths fx={} fy={}, expected positive", what,
               camera.fx, camera.fy);
  if (entry.contains("dist")) {
    const json& dist = entry["dist"];
    UNSEEN_CHECK(dist.is_array(), "{}: field \"dist\" must be an array, got {}", what, dist.dump());
    camera.distortion = bop::GetNumbers(entry, "dist", dist.size(), what);
  }
  return camera;
}

// Reads one camera's BOP scene folder (scene_camera.json, rgb/, depth/); ground truth is
// read separately once the object id is known. `static_rig`: extrinsics that change per
// frame are an error; otherwise (a plain BOP scene with a moving camera) the camera frame
// becomes the world frame.
CameraSource ReadBopCamera(const std::string& name, const fs::path& dir, bool static_rig,
                           std::vector<int>* frame_ids) {
  CameraSource source;
  source.name = name;
  source.dir = dir.string();
  const std::string camera_file = (dir / "scene_camera.json").string();
  const json cameras = bop::ReadJsonFile(camera_file);
  UNSEEN_CHECK(cameras.is_object() && !cameras.empty(),
               "{}: expected a non-empty JSON object keyed by frame id", camera_file);

  std::map<int, const json*> entries;
  for (const auto& [key, entry] : cameras.items()) {
    const int id = bop::ParseFrameId(key, camera_file);
    UNSEEN_CHECK(entry.is_object(), "{} frame {}: expected a JSON object, got {}", camera_file, key,
                 entry.dump());
    entries[id] = &entry;
  }

  bool first = true;
  std::vector<double> first_k;
  std::optional<Rigid3d> first_extrinsics;
  bool moving_camera = false;
  for (const auto& [id, entry_ptr] : entries) {
    const json& entry = *entry_ptr;
    const std::string what = fmt::format("{} frame {}", camera_file, id);
    const PinholeCamera k = ParseIntrinsics(entry, what);
    const std::vector<double> k_values = {k.fx, k.fy, k.cx, k.cy};
    double depth_scale = 1.0;
    if (entry.contains("depth_scale")) {
      depth_scale = bop::GetNumber(entry, "depth_scale", what);
      UNSEEN_CHECK(depth_scale > 0.0, "{}: field \"depth_scale\" is {}, expected positive", what,
                   depth_scale);
    }
    source.depth_scales.push_back(depth_scale);
    const bool has_r = entry.contains("cam_R_w2c");
    const bool has_t = entry.contains("cam_t_w2c");
    UNSEEN_CHECK(has_r == has_t, "{}: field \"{}\" is given without \"{}\"", what,
                 has_r ? "cam_R_w2c" : "cam_t_w2c", has_r ? "cam_t_w2c" : "cam_R_w2c");
    const Rigid3d cam_from_world =
        has_r ? bop::GetPoseMm(entry, "cam_R_w2c", "cam_t_w2c", what) : Rigid3d();
    if (first) {
      source.intrinsics = k;
      first_k = k_values;
      first_extrinsics = cam_from_world;
      first = false;
    } else {
      UNSEEN_CHECK(
          NearlyEqual(k_values, first_k) && NearlyEqual(k.distortion, source.intrinsics.distortion),
          "{}: intrinsics (cam_K/dist) differ from frame {}'s (fx={} fy={} cx={} cy={} "
          "vs fx={} fy={} cx={} cy={}); unseen assumes fixed intrinsics per camera",
          what, entries.begin()->first, k.fx, k.fy, k.cx, k.cy, first_k[0], first_k[1], first_k[2],
          first_k[3]);
      const PoseDifference d = Difference(cam_from_world, *first_extrinsics);
      if (d.translation > kExtrinsicsToleranceM || d.rotation_rad > kExtrinsicsToleranceRad) {
        UNSEEN_CHECK(!static_rig,
                     "{}: cam_R_w2c/cam_t_w2c differ from frame {}'s by {} mm / {} rad; the "
                     "cameras of a rig must be static",
                     what, entries.begin()->first, d.translation * 1e3, d.rotation_rad);
        moving_camera = true;
      }
    }
    frame_ids->push_back(id);
  }
  if (moving_camera) {
    UNSEEN_LOG_WARN(
        "{}: the camera moves (cam_R_w2c/cam_t_w2c change per frame); using the camera frame "
        "as the world frame",
        camera_file);
    source.world_from_cam = Rigid3d();
  } else {
    source.world_from_cam = first_extrinsics->Inverse();
  }

  // Images: rgb/<id>.png|.jpg, one per frame of scene_camera.json. A frame without its
  // file (a dropped frame) gets the path it should have had: reading it fails, naming it.
  const fs::path rgb_dir = dir / "rgb";
  UNSEEN_CHECK(IsFolder(rgb_dir), "{}: image folder not found", rgb_dir.string());
  const std::map<int, std::string> images = ListFrameFiles(rgb_dir, {".png", ".jpg", ".jpeg"});
  std::vector<int> missing;
  std::string first_present;
  for (int id : *frame_ids) {
    const auto it = images.find(id);
    if (it == images.end()) {
      missing.push_back(id);
      source.image_paths.push_back((rgb_dir / (bop::FrameName(id) + ".png")).string());
      continue;
    }
    if (first_present.empty()) first_present = it->second;
    source.image_paths.push_back(it->second);
  }
  UNSEEN_CHECK(!first_present.empty(),
               "{}: no image for frame {} of scene_camera.json (expected {}.png or {}.jpg)",
               rgb_dir.string(), frame_ids->front(), bop::FrameName(frame_ids->front()),
               bop::FrameName(frame_ids->front()));
  if (!missing.empty()) {
    UNSEEN_LOG_WARN(
        "{}: no image for {} of the {} frames of scene_camera.json (frame{} {}{}); "
        "they will be read as missing",
        rgb_dir.string(), missing.size(), frame_ids->size(), missing.size() > 1 ? "s" : "",
        fmt::join(missing.begin(), missing.begin() + std::min<size_t>(missing.size(), 5), ", "),
        missing.size() > 5 ? ", ..." : "");
  }
  const fs::path depth_dir = dir / "depth";
  if (IsFolder(depth_dir)) {
    const std::map<int, std::string> depths = ListFrameFiles(depth_dir, {".png"});
    int missing_depth = 0;
    for (int id : *frame_ids) {
      const auto it = depths.find(id);
      if (it == depths.end()) ++missing_depth;
      source.depth_paths.push_back(
          it != depths.end() ? it->second : (depth_dir / (bop::FrameName(id) + ".png")).string());
    }
    if (missing_depth > 0) {
      UNSEEN_LOG_WARN("{}: no depth image for {} of the {} frames; they will be read as missing",
                      depth_dir.string(), missing_depth, frame_ids->size());
    }
  }

  // Image size from the first image present.
  const cv::Mat first_image = cv::imread(first_present, cv::IMREAD_UNCHANGED);
  UNSEEN_CHECK(!first_image.empty(), "{}: not a readable image", first_present);
  source.intrinsics.width = first_image.cols;
  source.intrinsics.height = first_image.rows;
  source.intrinsics.Check(camera_file);
  source.PrepareUndistortion();
  return source;
}

// A camera's scene_gt.json, parsed once per open (BOP scenes' files run to many MB).
struct GroundTruthFile {
  std::string path;
  json doc;  // a JSON object keyed by frame id
};

// `dir`/scene_gt.json, or nothing when the folder has none.
std::optional<GroundTruthFile> LoadGroundTruthFile(const fs::path& dir) {
  const fs::path path = dir / "scene_gt.json";
  if (!Exists(path)) return std::nullopt;
  GroundTruthFile file{path.string(), bop::ReadJsonFile(path.string())};
  UNSEEN_CHECK(file.doc.is_object(), "{}: expected a JSON object keyed by frame id", file.path);
  return file;
}

// The first obj_id in a scene_gt.json (lowest frame id first), or 0 when it has none.
int FirstObjectId(const GroundTruthFile& gt) {
  std::map<int, const json*> frames;
  for (const auto& [key, list] : gt.doc.items()) frames[bop::ParseFrameId(key, gt.path)] = &list;
  for (const auto& [id, list] : frames) {
    const std::string what = fmt::format("{} frame {}", gt.path, id);
    UNSEEN_CHECK(list->is_array(), "{}: expected a list of objects, got {}", what, list->dump());
    if (!list->empty()) return bop::GetInt((*list)[0], "obj_id", what);
  }
  return 0;
}

// Every obj_id of a scene_gt.json.
std::set<int> ObjectIds(const GroundTruthFile& gt) {
  std::set<int> ids;
  for (const auto& [key, list] : gt.doc.items()) {
    const std::string what = fmt::format("{} frame {}", gt.path, key);
    UNSEEN_CHECK(list.is_array(), "{}: expected a list of objects, got {}", what, list.dump());
    for (const json& entry : list) ids.insert(bop::GetInt(entry, "obj_id", what));
  }
  return ids;
}

// The poses of object `obj_id` in `gt`, the scene_gt.json of `source` (entries of other
// objects are only checked for an integer obj_id). Frame ids must be frames of
// scene_camera.json.
void ReadGroundTruth(const GroundTruthFile& gt, int obj_id, const std::vector<int>& frame_ids,
                     CameraSource* source) {
  std::map<int, int> index_of;
  for (size_t i = 0; i < frame_ids.size(); ++i) index_of[frame_ids[i]] = static_cast<int>(i);
  source->cam_from_obj.assign(frame_ids.size(), std::nullopt);
  for (const auto& [key, list] : gt.doc.items()) {
    const int id = bop::ParseFrameId(key, gt.path);
    const std::string what = fmt::format("{} frame {}", gt.path, id);
    UNSEEN_CHECK(index_of.count(id), "{}: frame {} is not in scene_camera.json", gt.path, id);
    UNSEEN_CHECK(list.is_array(), "{}: expected a list of objects, got {}", what, list.dump());
    for (const json& entry : list) {
      if (bop::GetInt(entry, "obj_id", what) != obj_id) continue;
      source->cam_from_obj[index_of[id]] = bop::GetPoseMm(entry, "cam_R_m2c", "cam_t_m2c", what);
      break;  // the first instance of the object
    }
  }
  source->has_gt = true;
  if (std::none_of(source->cam_from_obj.begin(), source->cam_from_obj.end(),
                   [](const std::optional<Rigid3d>& p) { return p.has_value(); })) {
    UNSEEN_LOG_WARN("{}: no frame has object {}; camera {} has no ground truth for it", gt.path,
                    obj_id, source->name);
  }
}

// models/obj_<id>.<ext> in the first of `dirs` that has one, or "".
std::string FindModel(const std::vector<fs::path>& dirs, int obj_id) {
  if (obj_id <= 0) return "";
  for (const fs::path& dir : dirs) {
    for (const char* ext : {".ply", ".obj", ".gltf", ".glb"}) {
      const fs::path p = dir / fmt::format("obj_{:06d}{}", obj_id, ext);
      if (IsFile(p)) return fs::absolute(p).lexically_normal().string();
    }
  }
  return "";
}

}  // namespace

struct Sequence::Impl {
  Kind kind = Kind::kBop;
  std::string path;
  double fps = 30.0;
  std::vector<CameraSource> sources;  // every camera of the sequence
  std::vector<int> selected;          // rig camera i is sources[selected[i]]
  int reference_source = 0;           // index into sources
  Rig rig;
  int reference = 0;  // index into rig
  std::vector<int> frame_ids;
  int obj_id = 0;
  std::string model_path;

  // Video state: the capture reads sequentially; next_video_index is the frame it gives next.
  mutable std::mutex video_mutex;
  mutable cv::VideoCapture capture;
  mutable int next_video_index = 0;

  void BuildRig() {
    rig.cameras.clear();
    reference = 0;
    for (size_t i = 0; i < selected.size(); ++i) {
      const CameraSource& s = sources[selected[i]];
      RigCamera camera;
      camera.name = s.name;
      camera.intrinsics = s.intrinsics;
      camera.intrinsics.distortion.clear();  // frames are delivered undistorted
      camera.world_from_cam = s.world_from_cam;
      rig.cameras.push_back(camera);
      if (selected[i] == reference_source) reference = static_cast<int>(i);
    }
  }

  void CheckIndex(int index) const {
    UNSEEN_CHECK(index >= 0 && index < static_cast<int>(frame_ids.size()),
                 "{}: frame index {} out of range [0, {})", path, index, frame_ids.size());
  }

  // Frame `index` of the selected cameras. `strict`: an image that cannot be read throws;
  // otherwise it is left empty and described in Frame::errors.
  Frame Read(int index, bool strict) const;

  cv::Mat ReadVideoFrame(int index) const {
    std::lock_guard<std::mutex> lock(video_mutex);
    if (index != next_video_index) capture.set(cv::CAP_PROP_POS_FRAMES, index);
    cv::Mat raw;
    const bool ok = capture.read(raw);
    next_video_index = ok ? index + 1 : -1;
    UNSEEN_CHECK(ok && !raw.empty(), "{}: cannot read video frame {}", path, index);
    return ToFloatBgr(raw, fmt::format("{} frame {}", path, index));
  }
};

Sequence::Sequence(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Sequence::Sequence(Sequence&&) noexcept = default;
Sequence& Sequence::operator=(Sequence&&) noexcept = default;
Sequence::~Sequence() = default;

Sequence Sequence::Open(const std::string& path, int obj_id) {
  UNSEEN_CHECK(IsFolder(path), "{}: sequence folder not found", path);
  UNSEEN_CHECK(obj_id >= 0, "{}: object id {} must be positive (0: the sequence's own)", path,
               obj_id);
  auto impl = std::make_unique<Impl>();
  impl->kind = Kind::kBop;
  impl->path = path;
  const fs::path root(path);
  const fs::path sequence_file = root / "sequence.json";

  std::vector<std::string> names;
  std::vector<fs::path> dirs;
  std::string reference_name;
  std::optional<int> declared_obj_id;
  std::string declared_model;
  const bool has_sequence_file = IsFile(sequence_file);
  if (has_sequence_file) {
    const std::string file = sequence_file.string();
    const json seq = bop::ReadJsonFile(file);
    UNSEEN_CHECK(seq.is_object(), "{}: expected a JSON object", file);
    UNSEEN_CHECK(seq.contains("cameras"), "{}: field \"cameras\" is missing", file);
    const json& cameras = seq["cameras"];
    UNSEEN_CHECK(cameras.is_array() && !cameras.empty(),
                 "{}: field \"cameras\" must be a non-empty list of folder names, got {}", file,
                 cameras.dump());
    for (const json& c : cameras) {
      UNSEEN_CHECK(c.is_string() && !c.get<std::string>().empty(),
                   "{}: field \"cameras\" holds {}, expected folder names", file, c.dump());
      const std::string name = c.get<std::string>();
      UNSEEN_CHECK(std::find(names.begin(), names.end(), name) == names.end(),
                   "{}: field \"cameras\" names \"{}\" twice", file, name);
      const fs::path dir = root / name;
      UNSEEN_CHECK(IsFolder(dir), "{}: camera \"{}\" has no folder {}", file, name,
                   dir.string());
      names.push_back(name);
      dirs.push_back(dir);
    }
    if (seq.contains("fps")) {
      impl->fps = bop::GetNumber(seq, "fps", file);
      UNSEEN_CHECK(impl->fps > 0.0, "{}: field \"fps\" is {}, expected positive", file, impl->fps);
    }
    reference_name = names.front();
    if (seq.contains("reference_camera")) {
      const json& ref = seq["reference_camera"];
      UNSEEN_CHECK(ref.is_string(), "{}: field \"reference_camera\" is {}, expected a name", file,
                   ref.dump());
      reference_name = ref.get<std::string>();
      UNSEEN_CHECK(std::find(names.begin(), names.end(), reference_name) != names.end(),
                   "{}: field \"reference_camera\" is \"{}\", which is not in \"cameras\"", file,
                   reference_name);
    }
    if (seq.contains("object")) {
      const json& object = seq["object"];
      UNSEEN_CHECK(object.is_object(), "{}: field \"object\" is {}, expected an object", file,
                   object.dump());
      if (object.contains("obj_id")) {
        declared_obj_id = bop::GetInt(object, "obj_id", file + " field \"object\"");
        UNSEEN_CHECK(*declared_obj_id > 0, "{}: field \"object.obj_id\" is {}, expected > 0", file,
                     *declared_obj_id);
      }
      if (object.contains("model")) {
        UNSEEN_CHECK(object["model"].is_string(),
                     "{}: field \"object.model\" is {}, expected a path", file,
                     object["model"].dump());
        declared_model = object["model"].get<std::string>();
        const fs::path model = root / declared_model;
        UNSEEN_CHECK(IsFile(model), "{}: field \"object.model\": file {} not found",
                     file, model.string());
        impl->model_path = fs::absolute(model).lexically_normal().string();
      }
    }
  } else {
    UNSEEN_CHECK(IsFile(root / "scene_camera.json"),
                 "{}: not a sequence folder (neither sequence.json nor scene_camera.json found)",
                 path);
    std::string name = fs::absolute(root).lexically_normal().filename().string();
    if (name.empty())
      name = fs::absolute(root).lexically_normal().parent_path().filename().string();
    names.push_back(name.empty() ? "cam0" : name);
    dirs.push_back(root);
    reference_name = names.front();
  }

  // Cameras, then frame ids that agree across them.
  std::vector<std::vector<int>> ids(names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    impl->sources.push_back(ReadBopCamera(names[i], dirs[i], has_sequence_file, &ids[i]));
  }
  for (size_t i = 1; i < names.size(); ++i) {
    const std::string file = (dirs[i] / "scene_camera.json").string();
    const std::set<int> a(ids[0].begin(), ids[0].end()), b(ids[i].begin(), ids[i].end());
    for (int id : ids[0]) {
      UNSEEN_CHECK(b.count(id), "{}: camera {} lacks frame {}, which camera {} has", file, names[i],
                   id, names[0]);
    }
    for (int id : ids[i]) {
      UNSEEN_CHECK(a.count(id), "{}: camera {} has frame {}, which camera {} lacks", file, names[i],
                   id, names[0]);
    }
  }
  impl->frame_ids = ids[0];
  impl->reference_source =
      static_cast<int>(std::find(names.begin(), names.end(), reference_name) - names.begin());

  // Object id: sequence.json's, else the first object in the ground truth; the caller's
  // when given (then sequence.json's model, another object's, is not used).
  std::vector<std::optional<GroundTruthFile>> gt_files;
  for (const fs::path& dir : dirs) gt_files.push_back(LoadGroundTruthFile(dir));
  if (declared_obj_id) {
    impl->obj_id = *declared_obj_id;
  } else {
    std::vector<size_t> order = {static_cast<size_t>(impl->reference_source)};
    for (size_t i = 0; i < names.size(); ++i) order.push_back(i);
    for (size_t i : order) {
      if (gt_files[i]) {
        impl->obj_id = FirstObjectId(*gt_files[i]);
        if (impl->obj_id != 0) break;
      }
    }
  }
  if (obj_id > 0 && obj_id != impl->obj_id) {
    std::set<int> present;
    bool any_gt = false;
    for (const std::optional<GroundTruthFile>& gt : gt_files) {
      if (!gt) continue;
      any_gt = true;
      const std::set<int> ids = ObjectIds(*gt);
      present.insert(ids.begin(), ids.end());
    }
    UNSEEN_CHECK(!any_gt || present.count(obj_id),
                 "{}: object {} is in no frame of its scene_gt.json (objects there: {})", path,
                 obj_id, fmt::join(present, ", "));
    impl->obj_id = obj_id;
    impl->model_path.clear();
  }
  for (size_t i = 0; i < impl->sources.size(); ++i) {
    if (!gt_files[i]) continue;
    ReadGroundTruth(*gt_files[i], impl->obj_id, impl->frame_ids, &impl->sources[i]);
  }
  if (impl->model_path.empty()) {
    std::vector<fs::path> model_dirs = {root / "models"};
    if (!has_sequence_file) {  // BOP datasets keep models/ beside test/<scene>/
      model_dirs.push_back(root / ".." / "models");
      model_dirs.push_back(root / ".." / ".." / "models");
    }
    impl->model_path = FindModel(model_dirs, impl->obj_id);
  }

  for (size_t i = 0; i < names.size(); ++i) impl->selected.push_back(static_cast<int>(i));
  impl->BuildRig();
  impl->rig.Check();
  return Sequence(std::move(impl));
}

Sequence Sequence::OpenVideo(const std::string& path, const PinholeCamera& camera, double fps) {
  UNSEEN_CHECK(IsFile(path), "{}: video file not found", path);
  UNSEEN_CHECK(std::isfinite(fps) && fps > 0.0, "{}: fps {} must be positive", path, fps);
  auto impl = std::make_unique<Impl>();
  impl->kind = Kind::kVideo;
  impl->path = path;
  impl->fps = fps;
  // FFmpeg decodes every container and codec a file may hold; asking it alone keeps
  // OpenCV from probing camera back-ends (gphoto2, libusb) for a file name.
  UNSEEN_CHECK(impl->capture.open(path, cv::CAP_FFMPEG) && impl->capture.isOpened(),
               "{}: cannot open video (FFmpeg cannot decode it)", path);
  cv::Mat first;
  UNSEEN_CHECK(impl->capture.read(first) && !first.empty(), "{}: video has no readable frame",
               path);
  int count = static_cast<int>(impl->capture.get(cv::CAP_PROP_FRAME_COUNT));
  impl->next_video_index = 1;
  if (count <= 0) {  // unknown length: read through once
    count = 1;
    while (impl->capture.grab()) ++count;
    impl->next_video_index = count;
  }
  CameraSource source;
  source.name = "cam0";
  source.intrinsics = camera;
  if (source.intrinsics.width == 0 && source.intrinsics.height == 0) {
    source.intrinsics.width = first.cols;
    source.intrinsics.height = first.rows;
  }
  source.CheckSize(first, path);
  source.intrinsics.Check(path + " camera");
  source.PrepareUndistortion();
  impl->sources.push_back(std::move(source));
  for (int i = 0; i < count; ++i) impl->frame_ids.push_back(i);
  impl->selected = {0};
  impl->BuildRig();
  return Sequence(std::move(impl));
}

Sequence Sequence::OpenImageFolder(const std::string& path, const PinholeCamera& camera,
                                   double fps) {
  UNSEEN_CHECK(IsFolder(path), "{}: image folder not found", path);
  UNSEEN_CHECK(std::isfinite(fps) && fps > 0.0, "{}: fps {} must be positive", path, fps);
  auto impl = std::make_unique<Impl>();
  impl->kind = Kind::kImageFolder;
  impl->path = path;
  impl->fps = fps;
  CameraSource source;
  source.name = "cam0";
  const std::set<std::string> extensions = {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff"};
  for (const fs::directory_entry& entry : fs::directory_iterator(path)) {
    if (entry.is_regular_file() && extensions.count(Lower(entry.path().extension().string()))) {
      source.image_paths.push_back(entry.path().string());
    }
  }
  UNSEEN_CHECK(!source.image_paths.empty(),
               "{}: no images (.png, .jpg, .jpeg, .bmp, .tif) in the folder", path);
  std::sort(source.image_paths.begin(), source.image_paths.end());
  const cv::Mat first = cv::imread(source.image_paths.front(), cv::IMREAD_UNCHANGED);
  UNSEEN_CHECK(!first.empty(), "{}: not a readable image", source.image_paths.front());
  source.intrinsics = camera;
  if (source.intrinsics.width == 0 && source.intrinsics.height == 0) {
    source.intrinsics.width = first.cols;
    source.intrinsics.height = first.rows;
  }
  source.CheckSize(first, source.image_paths.front());
  source.intrinsics.Check(path + " camera");
  source.PrepareUndistortion();
  for (size_t i = 0; i < source.image_paths.size(); ++i) {
    impl->frame_ids.push_back(static_cast<int>(i));
  }
  impl->sources.push_back(std::move(source));
  impl->selected = {0};
  impl->BuildRig();
  return Sequence(std::move(impl));
}

const std::string& Sequence::path() const { return impl_->path; }
const Rig& Sequence::rig() const { return impl_->rig; }
int Sequence::reference_camera() const { return impl_->reference; }
double Sequence::fps() const { return impl_->fps; }
int Sequence::num_frames() const { return static_cast<int>(impl_->frame_ids.size()); }

int Sequence::frame_id(int index) const {
  impl_->CheckIndex(index);
  return impl_->frame_ids[index];
}

Frame Sequence::Impl::Read(int index, bool strict) const {
  CheckIndex(index);
  Frame frame;
  frame.frame_id = frame_ids[index];
  frame.time_s = frame.frame_id / fps;
  const bool depth = std::any_of(selected.begin(), selected.end(),
                                 [&](int i) { return !sources[i].depth_paths.empty(); });
  // Runs `read`; when not strict, a failure is recorded and gives an empty image.
  auto attempt = [&](int camera, bool is_depth, const std::string& file, auto&& read) {
    if (strict) return read();
    try {
      return read();
    } catch (const Error& e) {
      frame.errors.push_back({camera, is_depth, file, e.what()});
    } catch (const cv::Exception& e) {  // a decoder that gave up on a damaged file
      frame.errors.push_back({camera, is_depth, file, fmt::format("{}: {}", file, e.what())});
    }
    return cv::Mat();
  };
  for (int c = 0; c < static_cast<int>(selected.size()); ++c) {
    const CameraSource& source = sources[selected[c]];
    const std::string file = kind == Kind::kVideo ? fmt::format("{} frame {}", path, index)
                                                  : source.image_paths[index];
    frame.images.push_back(attempt(c, false, file, [&] {
      cv::Mat image;
      if (kind == Kind::kVideo) {
        image = ReadVideoFrame(index);
      } else {
        image = LoadColorImage(file);
      }
      source.CheckSize(image, file);
      return source.Undistort(image, cv::INTER_LINEAR);
    }));
    if (!depth) continue;
    if (source.depth_paths.empty()) {
      frame.depths.emplace_back();
      continue;
    }
    const std::string& depth_file = source.depth_paths[index];
    frame.depths.push_back(attempt(c, true, depth_file, [&] {
      const cv::Mat raw = cv::imread(depth_file, cv::IMREAD_ANYDEPTH);
      UNSEEN_CHECK(!raw.empty(), "{}: depth image missing or unreadable", depth_file);
      UNSEEN_CHECK(raw.type() == CV_16UC1, "{}: depth image must be 16-bit single channel",
                   depth_file);
      source.CheckSize(raw, depth_file);
      cv::Mat depth_m;
      raw.convertTo(depth_m, CV_32F, source.depth_scales[index] * 1e-3);
      return source.Undistort(depth_m, cv::INTER_NEAREST);
    }));
  }
  return frame;
}

Frame Sequence::ReadFrame(int index) const { return impl_->Read(index, true); }

Frame Sequence::TryReadFrame(int index) const { return impl_->Read(index, false); }

void Sequence::SelectCameras(const std::vector<std::string>& names) {
  UNSEEN_CHECK(!names.empty(), "{}: no cameras selected", impl_->path);
  std::vector<int> selected;
  for (const std::string& name : names) {
    int found = -1;
    for (size_t i = 0; i < impl_->sources.size(); ++i) {
      if (impl_->sources[i].name == name) found = static_cast<int>(i);
    }
    std::vector<std::string> all;
    for (const CameraSource& s : impl_->sources) all.push_back(s.name);
    UNSEEN_CHECK(found >= 0, "{}: unknown camera \"{}\" (the sequence has {})", impl_->path, name,
                 fmt::join(all, ", "));
    UNSEEN_CHECK(std::find(selected.begin(), selected.end(), found) == selected.end(),
                 "{}: camera \"{}\" selected twice", impl_->path, name);
    selected.push_back(found);
  }
  impl_->selected = selected;
  impl_->BuildRig();
}

bool Sequence::has_depth() const {
  for (int i : impl_->selected) {
    if (!impl_->sources[i].depth_paths.empty()) return true;
  }
  return false;
}

bool Sequence::has_ground_truth() const {
  for (int i : impl_->selected) {
    if (impl_->sources[i].has_gt) return true;
  }
  return false;
}

std::optional<Rigid3d> Sequence::GroundTruth(int index) const {
  impl_->CheckIndex(index);
  if (impl_->sources[impl_->selected[impl_->reference]].has_gt) {
    return GroundTruthFromCamera(index, impl_->reference);
  }
  for (int c = 0; c < static_cast<int>(impl_->selected.size()); ++c) {
    if (impl_->sources[impl_->selected[c]].has_gt) return GroundTruthFromCamera(index, c);
  }
  return std::nullopt;
}

std::optional<Rigid3d> Sequence::GroundTruthFromCamera(int index, int camera) const {
  impl_->CheckIndex(index);
  UNSEEN_CHECK(camera >= 0 && camera < static_cast<int>(impl_->selected.size()),
               "{}: camera index {} out of range [0, {})", impl_->path, camera,
               impl_->selected.size());
  const CameraSource& source = impl_->sources[impl_->selected[camera]];
  if (!source.has_gt || !source.cam_from_obj[index]) return std::nullopt;
  return source.world_from_cam * *source.cam_from_obj[index];
}

int Sequence::obj_id() const { return impl_->obj_id; }
std::string Sequence::model_path() const { return impl_->model_path; }

Mesh Sequence::LoadModel() const {
  UNSEEN_CHECK(!impl_->model_path.empty(),
               "{}: the sequence has no object model (no sequence.json \"object.model\" and no "
               "models/obj_{:06d}.ply|obj|gltf|glb)",
               impl_->path, impl_->obj_id);
  return LoadMesh(impl_->model_path, 0.001);
}

}  // namespace unseen
