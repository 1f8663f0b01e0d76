// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/mesh/projector_io.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <system_error>
#include <utility>

#include "unseen/image/image_io.h"
#include "unseen/util/error.h"
#include "unseen/util/files.h"

namespace unseen {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Value of field `key` of `object`, or an error naming the file and field.
template <typename T>
T GetField(const json& object, const std::string& key, const std::string& file,
           const std::string& where) {
  UNSEEN_CHECK(object.is_object() && object.contains(key), "{}: {} has no field '{}'", file, where,
               key);
  try {
    return object.at(key).get<T>();
  } catch (const json::exception& e) {
    ThrowError("{}: {}.{} has the wrong type ({}): {}", file, where, key, object.at(key).dump(),
               e.what());
  }
}

}  // namespace

fs::path ProjectorsPath(const fs::path& mesh_path) {
  return mesh_path.parent_path() / (mesh_path.stem().string() + "_projectors.json");
}

std::vector<Projector> ReadProjectors(const fs::path& json_path) {
  const std::string file = json_path.string();
  std::ifstream in(json_path);
  UNSEEN_CHECK(in.good(), "{}: cannot open projector file", file);
  // Nesting is limited: the value is copied and printed recursively below.
  constexpr int kMaxDepth = 64;
  const json::parser_callback_t limit_depth = [&](int depth, json::parse_event_t, json&) {
    UNSEEN_CHECK(depth <= kMaxDepth, "{}: JSON nested deeper than {} levels", file, kMaxDepth);
    return true;
  };
  json root;
  try {
    root = json::parse(in, limit_depth);
  } catch (const json::exception& e) {
    ThrowError("{}: malformed JSON: {}", file, e.what());
  }
  UNSEEN_CHECK(root.is_object() && root.contains("projectors") && root["projectors"].is_array(),
               "{}: expected an object with a 'projectors' array", file);
  std::vector<Projector> projectors;
  const json& list = root["projectors"];
  for (size_t i = 0; i < list.size(); ++i) {
    const json& p = list[i];
    const std::string where = "projectors[" + std::to_string(i) + "]";
    Projector projector;
    const json camera = GetField<json>(p, "camera", file, where);
    const std::string cwhere = where + ".camera";
    PinholeCamera& cam = projector.camera;
    cam.width = GetField<int>(camera, "width", file, cwhere);
    cam.height = GetField<int>(camera, "height", file, cwhere);
    cam.fx = GetField<double>(camera, "fx", file, cwhere);
    cam.fy = GetField<double>(camera, "fy", file, cwhere);
    cam.cx = GetField<double>(camera, "cx", file, cwhere);
    cam.cy = GetField<double>(camera, "cy", file, cwhere);
    if (camera.contains("distortion")) {
      cam.distortion = GetField<std::vector<double>>(camera, "distortion", file, cwhere);
    }
    cam.Check(file + " " + cwhere);

    const json pose = GetField<json>(p, "cam_from_obj", file, where);
    const std::string pwhere = where + ".cam_from_obj";
    const auto rows = GetField<std::vector<std::vector<double>>>(pose, "rotation", file, pwhere);
    const auto t = GetField<std::vector<double>>(pose, "translation", file, pwhere);
    UNSEEN_CHECK(
        rows.size() == 3 && rows[0].size() == 3 && rows[1].size() == 3 && rows[2].size() == 3,
        "{}: {}.rotation must be 3x3, got {}", file, pwhere, pose["rotation"].dump());
    UNSEEN_CHECK(t.size() == 3, "{}: {}.translation must have 3 entries, got {}", file, pwhere,
                 pose["translation"].dump());
    Eigen::Matrix3d rotation;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) rotation(r, c) = rows[r][c];
    }
    const Eigen::Vector3d translation(t[0], t[1], t[2]);
    UNSEEN_CHECK(translation.allFinite(), "{}: {}.translation is not finite: {}", file, pwhere,
                 pose["translation"].dump());
    projector.cam_from_obj =
        Rigid3d::FromRotationMatrix(rotation, translation, file + " " + pwhere + ".rotation");

    const std::string image_name = GetField<std::string>(p, "image", file, where);
    const fs::path image_path = json_path.parent_path() / image_name;
    UNSEEN_CHECK(IsFile(image_path), "{}: {}.image '{}' not found", file, where,
                 image_path.string());
    projector.image = LoadColorImage(image_path.string());
    UNSEEN_CHECK(projector.image.cols == cam.width && projector.image.rows == cam.height,
                 "{}: {}.image '{}' is {}x{} but the camera is {}x{}", file, where, image_name,
                 projector.image.cols, projector.image.rows, cam.width, cam.height);
    if (p.contains("depth")) {
      // The surface the projector saw (self-occlusion), 16-bit, in the mesh file's units.
      const std::string depth_name = GetField<std::string>(p, "depth", file, where);
      const double depth_scale = GetField<double>(p, "depth_scale", file, where);
      const double tolerance = GetField<double>(p, "depth_tolerance", file, where);
      UNSEEN_CHECK(depth_scale > 0.0 && std::isfinite(depth_scale) && tolerance >= 0.0 &&
                       std::isfinite(tolerance),
                   "{}: {}.depth_scale {} must be > 0 and depth_tolerance {} >= 0", file, where,
                   depth_scale, tolerance);
      const fs::path depth_path = json_path.parent_path() / depth_name;
      const cv::Mat depth = cv::imread(depth_path.string(), cv::IMREAD_ANYDEPTH);
      UNSEEN_CHECK(depth.type() == CV_16UC1 && depth.cols == cam.width && depth.rows == cam.height,
                   "{}: {}.depth '{}' must be a 16-bit image of the camera's {}x{} pixels", file,
                   where, depth_path.string(), cam.width, cam.height);
      depth.convertTo(projector.depth, CV_32FC1, depth_scale);
      projector.depth_tolerance_m = static_cast<float>(tolerance);  // file units until Scale
    }
    projectors.push_back(std::move(projector));
  }
  return projectors;
}

void SaveProjectors(const Mesh& mesh, const fs::path& mesh_path, float scale) {
  const fs::path json_path = ProjectorsPath(mesh_path);
  std::error_code ec;
  if (mesh.projectors.empty()) {
    fs::remove(json_path, ec);  // a stale file would be read back by LoadMesh
    return;
  }
  json list = json::array();
  for (size_t i = 0; i < mesh.projectors.size(); ++i) {
    const Projector& p = mesh.projectors[i];
    const std::string image_name =
        fmt::format("{}_projector_{:03d}.png", mesh_path.stem().string(), i);
    SaveColorImage((mesh_path.parent_path() / image_name).string(), p.image);
    const Eigen::Matrix3d r = p.cam_from_obj.RotationMatrix();
    const Eigen::Vector3d t = p.cam_from_obj.translation() * static_cast<double>(scale);
    json camera = {{"width", p.camera.width},
                   {"height", p.camera.height},
                   {"fx", p.camera.fx},
                   {"fy", p.camera.fy},
                   {"cx", p.camera.cx},
                   {"cy", p.camera.cy},
                   {"distortion", p.camera.distortion}};
    json pose = {
        {"rotation",
         {{r(0, 0), r(0, 1), r(0, 2)}, {r(1, 0), r(1, 1), r(1, 2)}, {r(2, 0), r(2, 1), r(2, 2)}}},
        {"translation", {t.x(), t.y(), t.z()}}};
    json entry = {{"image", image_name}, {"camera", camera}, {"cam_from_obj", pose}};
    if (!p.depth.empty()) {
      double max_depth = 0.0;
      cv::minMaxLoc(p.depth, nullptr, &max_depth);
      // File units per count: the farthest point at 60 000 counts.
      const double depth_scale = std::max(max_depth * scale / 60000.0, 1e-9);
      cv::Mat counts;
      p.depth.convertTo(counts, CV_16UC1, scale / depth_scale);
      const std::string depth_name =
          fmt::format("{}_projector_{:03d}_depth.png", mesh_path.stem().string(), i);
      const std::string depth_path = (mesh_path.parent_path() / depth_name).string();
      UNSEEN_CHECK(cv::imwrite(depth_path, counts), "{}: cannot write", depth_path);
      entry["depth"] = depth_name;
      entry["depth_scale"] = depth_scale;
      entry["depth_tolerance"] = p.depth_tolerance_m * scale;
    }
    list.push_back(entry);
  }
  json root = {
      {"comment", "Projective textures of " + mesh_path.filename().string() +
                      ": image, pinhole intrinsics (pixels, pixel-centre origin), "
                      "cam_from_obj (rotation row-major, translation in the mesh file's units) "
                      "and optionally the depth it saw (16-bit PNG; count x depth_scale = the "
                      "mesh file's units) with its occlusion tolerance"},
      {"projectors", list}};
  std::ofstream out(json_path);
  UNSEEN_CHECK(out.good(), "{}: cannot open for writing", json_path.string());
  out << root.dump(1) << "\n";
  UNSEEN_CHECK(out.good(), "{}: write failed", json_path.string());
}

}  // namespace unseen
