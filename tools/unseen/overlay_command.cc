// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// `unseen overlay SEQ POSES OUT`: draws the model's outline at the estimated pose (green
// while tracking, red when lost) and at the ground truth (blue) over the frames, to a video
// (.mp4 / .avi) or a folder of PNG frames.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "tools/unseen/commands.h"
#include "unseen/eval/overlay.h"
#include "unseen/eval/sequence_poses.h"
#include "unseen/io/sequence.h"
#include "unseen/util/error.h"
#include "unseen/util/files.h"
#include "unseen/util/logging.h"

namespace unseen::cli {
namespace {

struct OverlayArgs {
  int obj_id = 0;  // --obj-id; 0: the sequence's own object
  std::string sequence;
  std::string poses;
  std::string bop_camera;
  std::string out;
  std::string camera;
  double fps = 0.0;
  bool no_ground_truth = false;
  int thickness_px = 2;
};

void RunOverlay(const OverlayArgs& args) {
  namespace fs = std::filesystem;
  UNSEEN_CHECK(Exists(args.sequence), "overlay: sequence '{}' does not exist", args.sequence);
  UNSEEN_CHECK(IsFile(args.poses), "overlay: pose file '{}' does not exist",
               args.poses);
  UNSEEN_CHECK(std::isfinite(args.fps) && args.fps >= 0.0,
               "overlay: --fps must be > 0 (or 0 for the sequence's), got {}", args.fps);
  Sequence sequence = Sequence::Open(args.sequence, args.obj_id);
  const std::vector<PoseRecord> poses = ReadPosesForSequence(args.poses, sequence, args.bop_camera);
  const std::string camera = args.camera.empty()
                                 ? sequence.rig().cameras.at(sequence.reference_camera()).name
                                 : args.camera;
  sequence.SelectCameras({camera});
  OverlayOptions options;
  options.draw_ground_truth = !args.no_ground_truth;
  options.line_thickness_px = args.thickness_px;
  options.show_progress = spdlog::get_level() <= spdlog::level::info;
  const int frames = WriteOverlay(sequence, poses, 0, args.out, args.fps, options);
  UNSEEN_LOG_INFO("overlay: wrote {} frames of camera {} to {}", frames, camera, args.out);
}

void AddOverlayCommand(CLI::App& app) {
  auto args = std::make_shared<OverlayArgs>();
  CLI::App* cmd = app.add_subcommand(
      "overlay",
      "Draw the model's outline at the estimated pose (green tracking, red lost) and at the "
      "ground truth (blue) over the frames; write a video (.mp4, .avi) or PNG frames (folder)");
  cmd->add_option("SEQ", args->sequence, "Sequence folder")->required();
  AddObjectIdOption(cmd, &args->obj_id);
  cmd->add_option("POSES", args->poses, "Pose stream (.csv, .jsonl) or BOP scene_gt.json")
      ->required();
  cmd->add_option("OUT", args->out, "Output .mp4 / .avi file, or a folder for PNG frames")
      ->required();
  cmd->add_option("--camera", args->camera, "Camera name (default: the reference camera)");
  cmd->add_option("--fps", args->fps, "Video frame rate (default: the sequence's)");
  cmd->add_option("--thickness", args->thickness_px, "Outline thickness, px")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--no-ground-truth", args->no_ground_truth, "Do not draw the ground truth");
  cmd->add_option("--bop-camera", args->bop_camera,
                  "Camera whose frame a BOP scene_gt.json POSES is in (default: the camera "
                  "folder holding it, else the reference camera)");
  cmd->callback([args] { RunOverlay(*args); });
}

}  // namespace

UNSEEN_REGISTER_COMMAND("overlay", AddOverlayCommand);

}  // namespace unseen::cli
