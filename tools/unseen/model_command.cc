// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// `unseen model SEQ --frame K (--roi x,y,w,h | --mask FILE | --init gt) --out model.ply`:
// builds one model of the object from frame K (SPEC 5), writes it with its projective
// texture (in millimetres, like a BOP model, so `unseen track --model` reads it as is) and
// prints its object frame for `unseen track --init`; --debug-dir writes the depth map,
// texturedness, the object's mask and the mesh over the image.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "tools/unseen/commands.h"
#include "tools/unseen/unknown_object.h"
#include "unseen/io/sequence.h"
#include "unseen/mesh/mesh_io.h"
#include "unseen/model/modeller.h"
#include "unseen/util/error.h"
#include "unseen/util/files.h"

namespace unseen::cli {
namespace {

struct ModelArgs {
  int obj_id = 0;  // --obj-id; 0: the sequence's own object
  std::string sequence;
  int frame = 0;
  UnknownObjectArgs object;
  std::string out;
  std::string debug_dir;
};

cv::Mat To8U(const cv::Mat& m, double lo, double hi) {
  cv::Mat out;
  m.convertTo(out, CV_8U, 255.0 / (hi - lo), -255.0 * lo / (hi - lo));
  return out;
}

void WriteDebugImages(const std::string& dir, const ModelBuild& build, const cv::Mat& image,
                      const PinholeCamera& camera, const Rigid3d& cam_from_obj) {
  std::filesystem::create_directories(dir);
  auto write = [&](const std::string& name, const cv::Mat& m) {
    const std::string path = (std::filesystem::path(dir) / name).string();
    UNSEEN_CHECK(cv::imwrite(path, m), "model: cannot write debug image '{}'", path);
  };
  // Depth: near red to far blue over the measured range, black where not measured.
  double lo = 0.0, hi = 1.0;
  cv::minMaxLoc(build.depth.depth, &lo, &hi, nullptr, nullptr, build.depth.depth > 0.0f);
  cv::Mat depth_colour;
  cv::applyColorMap(To8U(build.depth.depth, hi, lo - 1e-6), depth_colour, cv::COLORMAP_JET);
  depth_colour.setTo(cv::Scalar::all(0), build.depth.depth <= 0.0f);
  write("depth.png", depth_colour);
  cv::Mat log_t;
  cv::log(build.depth.texturedness + 1e-6, log_t);
  write("texturedness.png", To8U(log_t, std::log(1e-6), 0.0));
  if (!build.mask.empty()) write("mask.png", build.mask);
  cv::Mat overlay;
  image.convertTo(overlay, CV_8UC3, 255.0);
  if (build.mesh) {
    const Mesh& mesh = *build.mesh;
    std::vector<cv::Point> px(mesh.vertices.size());
    for (size_t i = 0; i < px.size(); ++i) {
      const Eigen::Vector2d p = camera.Project(cam_from_obj * mesh.vertices[i].cast<double>());
      px[i] = cv::Point(static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y())));
    }
    for (const Eigen::Vector3i& t : mesh.triangles) {
      for (int k = 0; k < 3; ++k) {
        cv::line(overlay, px[t[k]], px[t[(k + 1) % 3]], cv::Scalar(0, 255, 0), 1, cv::LINE_AA);
      }
    }
    for (const cv::Point& p : px) cv::circle(overlay, p, 2, cv::Scalar(0, 0, 255), cv::FILLED);
  }
  const PixelRect& r = build.region;
  cv::rectangle(overlay, cv::Rect(r.x0, r.y0, r.width(), r.height()), cv::Scalar(255, 0, 0));
  write("mesh_overlay.png", overlay);
}

void RunModel(const ModelArgs& args) {
  UNSEEN_CHECK(Exists(args.sequence), "model: sequence '{}' does not exist", args.sequence);
  const Sequence sequence = Sequence::Open(args.sequence, args.obj_id);
  UNSEEN_CHECK(args.frame >= 0 && args.frame < sequence.num_frames(),
               "model: --frame {} is outside [0, {})", args.frame, sequence.num_frames());
  const ModellerOptions options = ModellerOptionsFor(args.object, sequence, "model");
  const int reference = sequence.reference_camera();
  const Modeller modeller(sequence.rig(), reference, options);
  const Frame frame = sequence.ReadFrame(args.frame);
  const ObjectStart start =
      LocateUnknownObject(args.object, sequence, args.frame, frame, modeller, "model");
  const ModelBuild build = modeller.Build(frame, start.world_from_obj, start.region, start.mask);
  const RigCamera& camera = sequence.rig().cameras[reference];
  if (!args.debug_dir.empty()) {
    WriteDebugImages(args.debug_dir, build, frame.images[reference], camera.intrinsics,
                     camera.cam_from_world() * start.world_from_obj);
  }
  UNSEEN_CHECK(build.ok(), "model: cannot model the object in frame {} of '{}': {}", args.frame,
               args.sequence, build.why);
  SaveMesh(*build.mesh, args.out, 1000.0);
  const Eigen::Vector3d& t = start.world_from_obj.translation();
  const Eigen::Quaterniond& q = start.world_from_obj.rotation();
  std::printf(
      "model %s frame %d: %d vertices, %d triangles from %d of %d depth pixels (%s, "
      "%.1f ms depth, %.1f ms mesh) -> %s (mm)\n",
      args.sequence.c_str(), args.frame, build.mesh->num_vertices(), build.mesh->num_triangles(),
      build.depth.ValidPixels(), build.region.width() * build.region.height(),
      ToString(options.depth.source).c_str(), build.depth_ms, build.mesh_ms, args.out.c_str());
  std::printf(
      "  segmentation: region %d px, depth %d, on plane %d (found %d), beyond radius %d, "
      "unconnected %d, dense %d%s\n",
      build.segmentation.region_pixels, build.segmentation.with_depth, build.segmentation.on_plane,
      int(build.segmentation.plane_found), build.segmentation.beyond_radius,
      build.segmentation.unconnected, int(build.segmentation.dense),
      build.segmentation.FragmentedNote());
  std::printf("  object frame (track --init): %.6f,%.6f,%.6f,%.8f,%.8f,%.8f,%.8f\n", t.x(), t.y(),
              t.z(), q.x(), q.y(), q.z(), q.w());
}

void AddModelCommand(CLI::App& app) {
  auto args = std::make_shared<ModelArgs>();
  CLI::App* cmd = app.add_subcommand(
      "model",
      "Build a textured model of the object from one frame (depth, mesh, projective "
      "texture) and write it");
  cmd->add_option("SEQ", args->sequence, "Sequence folder")->required();
  AddObjectIdOption(cmd, &args->obj_id);
  cmd->add_option("--frame", args->frame, "Frame index to model");
  cmd->add_option("--init", args->object.init,
                  "gt: build in the ground truth's object frame (evaluation)");
  cmd->add_option("--roi", args->object.roi, "Object region x,y,w,h in the reference image");
  cmd->add_option("--mask", args->object.mask, "Object mask image (non-zero = object)");
  cmd->add_option("--depth", args->object.depth,
                  "Depth source: planesweep, stereo or sensor (default: sensor with depth "
                  "images, else stereo for two cameras, else planesweep)");
  cmd->add_option("--config", args->object.model_config, "Modeller options (YAML)");
  cmd->add_option("--out", args->out, "Model file to write (.ply/.obj, millimetres)")->required();
  cmd->add_option("--debug-dir", args->debug_dir,
                  "Write depth.png, texturedness.png, mask.png, mesh_overlay.png here");
  cmd->callback([args] { RunModel(*args); });
}

}  // namespace

UNSEEN_REGISTER_COMMAND("model", AddModelCommand);

}  // namespace unseen::cli
