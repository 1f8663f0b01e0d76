// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// `unseen run SOURCE`: the complete system (SPEC 6, system/system.h) on a sequence folder, a
// video file or image folder with its calibration, or a live camera (--camera N): learn the
// background, select the object, model it (or use --model), track it, and search again
// when it is lost. Writes the pose stream in the system's own object frame (score it with
// `unseen eval --align-first`) and prints the statuses, the speed and, when the source has
// ground truth, the error after aligning the first tracked pose. --config takes the whole
// system's YAML (system/system_config.h); the command line's options override it.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <opencv2/highgui.hpp>
#include <string>
#include <vector>

#include "tools/unseen/commands.h"
#include "tools/unseen/unknown_object.h"
#include "unseen/camera/calibration_io.h"
#include "unseen/eval/overlay.h"
#include "unseen/mesh/mesh_io.h"
#include "unseen/system/frame_source.h"
#include "unseen/system/system.h"
#include "unseen/system/system_config.h"
#include "unseen/system/system_overlay.h"
#include "unseen/system/tracking_session.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"

namespace unseen::cli {
namespace {

namespace fs = std::filesystem;

struct RunArgs {
  int obj_id = 0;  // --obj-id; 0: the sequence's own object
  std::string source;
  int camera = -1;  // live camera index
  std::string calibration;
  std::string model;
  std::string model_units = "mm";
  std::string config;  // system.yaml
  // Overrides of the configuration (empty / 0: as configured).
  std::string filters;
  std::string regions;
  std::string tracker_config;
  UnknownObjectArgs object;  // --depth, --model-config
  std::string update;
  int reselect_after = 0;
  std::string out;
  std::string overlay;
  bool show = false;
  int max_frames = 0;
};

bool IsSequenceFolder(const fs::path& p) {
  return fs::exists(p / "sequence.json") || fs::exists(p / "scene_camera.json");
}

std::unique_ptr<FrameSource> OpenSource(const RunArgs& args) {
  if (args.camera >= 0) {
    UNSEEN_CHECK(args.source.empty(), "run: give SOURCE or --camera, not both");
    UNSEEN_CHECK(!args.calibration.empty(), "run: --camera {} needs --calibration FILE",
                 args.camera);
    return std::make_unique<CaptureFrameSource>(args.camera,
                                                LoadCameraCalibration(args.calibration));
  }
  UNSEEN_CHECK(!args.source.empty(),
               "run: give SOURCE (a sequence folder, video or image "
               "folder) or --camera N");
  UNSEEN_CHECK(fs::exists(args.source), "run: source '{}' does not exist", args.source);
  if (fs::is_directory(args.source) && IsSequenceFolder(args.source)) {
    return std::make_unique<SequenceFrameSource>(Sequence::Open(args.source, args.obj_id));
  }
  UNSEEN_CHECK(!args.calibration.empty(),
               "run: '{}' is not a sequence folder: a video or image folder needs --calibration "
               "FILE",
               args.source);
  const PinholeCamera camera = LoadCameraCalibration(args.calibration);
  if (fs::is_directory(args.source)) {
    return std::make_unique<SequenceFrameSource>(Sequence::OpenImageFolder(args.source, camera));
  }
  // A video file is read as a live camera is (the same code path).
  return std::make_unique<CaptureFrameSource>(args.source, camera);
}

void RunSystem(const RunArgs& args) {
  std::unique_ptr<FrameSource> source = OpenSource(args);
  const Sequence* sequence = source->sequence();
  UNSEEN_CHECK(args.model_units == "mm" || args.model_units == "m",
               "run: --model-units '{}' must be mm or m", args.model_units);
  std::optional<Mesh> model;
  if (!args.model.empty()) model = LoadMesh(args.model, args.model_units == "mm" ? 0.001 : 1.0);

  SystemConfig config = args.config.empty() ? SystemConfig() : LoadSystemConfig(args.config);
  SystemOptions& options = config.system;
  if (!args.regions.empty()) options.regions = ParseRegionSource(args.regions, "run: --regions");
  if (args.reselect_after > 0) options.reselect_after_lost_frames = args.reselect_after;
  if (!args.update.empty()) {
    try {
      options.update.mode = ParseModelUpdateMode(args.update);
    } catch (const Error& e) {
      ThrowError("run: --update: {}", e.what());
    }
  }
  options.Check();
  TrackerOptions tracker_options =
      args.tracker_config.empty() ? config.tracker : LoadTrackerOptions(args.tracker_config);
  if (source->fps() > 0) tracker_options.frame_interval_s = 1.0 / source->fps();
  ModellerOptions modeller_options = config.modeller.value_or(ModellerOptions());
  if (!model) {
    if (sequence != nullptr &&
        (!config.modeller || !args.object.depth.empty() || !args.object.model_config.empty())) {
      modeller_options = ModellerOptionsFor(args.object, *sequence, "run");
    } else if (!args.object.model_config.empty()) {
      modeller_options = LoadModellerOptions(args.object.model_config, modeller_options);
    }
    UNSEEN_CHECK(modeller_options.depth.source != DepthSourceKind::kSensor ||
                     (sequence != nullptr && sequence->has_depth()),
                 "run: an object without --model is modelled from depth: '{}' has no depth "
                 "images and {} camera(s); give --model FILE, or a source with depth or with "
                 "two cameras or more",
                 source->name(), source->rig().size());
  }
  InterestFilterBank bank;
  if (!args.filters.empty()) {
    bank = LoadInterestFilterBank(args.filters);
  } else if (config.filters) {
    bank = std::move(*config.filters);
  } else {
    bank.Add(std::make_unique<MotionFilter>(MotionFilterOptions()));
  }
  const int reference = source->reference_camera();
  const RigCamera reference_camera = source->rig().cameras[reference];
  System system(source->rig(), reference, std::move(model), std::move(bank), options,
                tracker_options, modeller_options);

  // The overlay, drawn as the frames come: to a file and/or an on-screen window.
  std::unique_ptr<OverlaySink> overlay;
  const char* kWindow = "unseen run";
  if (args.show) {
    const char* display = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    UNSEEN_CHECK((display != nullptr && *display) || (wayland != nullptr && *wayland),
                 "run: --show needs a display (DISPLAY is not set); write the overlay with "
                 "--overlay FILE instead");
    cv::namedWindow(kWindow, cv::WINDOW_AUTOSIZE);
  }
  SessionOptions session_options;
  session_options.name = "run";
  session_options.max_frames = args.max_frames;
  session_options.read_ahead = false;  // the system's own pace, as a live camera delivers
  session_options.poses_file = args.out;
  TrackingSession session(*source, session_options);
  SystemStep last;  // the frame's step, for the overlay
  const SessionSummary summary = session.Run(
      [&](const Frame& frame) {
        for (const FrameReadError& e : frame.errors) {
          UNSEEN_LOG_WARN("run: frame {}: camera {}: {}", frame.frame_id, e.camera, e.message);
        }
        last = system.Step(frame);
        SessionStep out;
        out.track = last.track;
        out.status = ToString(last.status);
        out.tracking = last.status == SystemStatus::kTracking;
        out.note = last.note;
        return out;
      },
      [&](const Frame& frame, const SessionStep&, const SessionFrame&) {
        if (args.overlay.empty() && !args.show) return true;
        cv::Mat image =
            frame.images[reference].empty()
                ? cv::Mat(reference_camera.intrinsics.height, reference_camera.intrinsics.width,
                          CV_8UC3, cv::Scalar::all(0))
                : frame.images[reference].clone();
        const Mesh* drawn = system.tracker() != nullptr ? &system.tracker()->model() : nullptr;
        DrawSystemOverlay(last, drawn, reference_camera.intrinsics,
                          reference_camera.cam_from_world(), SystemOverlayOptions(), &image);
        if (!args.overlay.empty()) {
          if (!overlay) {
            overlay = std::make_unique<OverlaySink>(
                args.overlay, source->fps() > 0 ? source->fps() : 30.0, image.size());
          }
          overlay->Write(image, frame.frame_id);
        }
        if (args.show) {
          cv::imshow(kWindow, image);
          const int key = cv::waitKey(1);
          if (key == 'q' || key == 27) return false;  // q or Esc ends the run
        }
        return true;
      });
  std::printf("run %s: %d frames, %.1f fps (%.2f ms/frame)\n", source->name().c_str(),
              summary.frames, summary.fps(), summary.mean_ms());
  std::printf("  frames:");
  for (const SystemStatus s : {SystemStatus::kLearning, SystemStatus::kNoObject,
                               SystemStatus::kTracking, SystemStatus::kLost}) {
    std::printf(" %s %d", ToString(s), summary.count(ToString(s)));
  }
  std::printf("\n");
  if (summary.truth_frames > 0) {
    std::printf(
        "  against ground truth after aligning the first tracked pose: %d of %d frames "
        "(%.1f %%) within 5 cm/5 deg; mean %.2f mm %.3f deg over the %d tracked\n",
        summary.within, summary.truth_frames, 100.0 * summary.within / summary.truth_frames,
        summary.aligned.mean_mm(), summary.aligned.mean_deg(), summary.aligned.frames);
  }
}

void AddRunCommand(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run", "The whole system: select the object, model it (or --model), track it");
  cmd->add_option("SOURCE", args->source,
                  "Sequence folder, video file or image folder (the latter two with "
                  "--calibration)");
  AddObjectIdOption(cmd, &args->obj_id);
  cmd->add_option("--camera", args->camera, "Live camera index (OpenCV VideoCapture)");
  cmd->add_option("--calibration", args->calibration,
                  "Camera calibration (OpenCV YAML/XML/JSON or ROS camera_info)");
  cmd->add_option("--model", args->model, "The object's model; without it, modelled on-line");
  cmd->add_option("--model-units", args->model_units, "Units of --model: mm (BOP) or m");
  cmd->add_option("--config", args->config,
                  "The system's configuration (YAML: filters, regions, selection, tracker, "
                  "...; configs/system/)");
  cmd->add_option("--filters", args->filters,
                  "Interest filter bank (YAML; default: the configuration's, else motion)");
  cmd->add_option("--regions", args->regions,
                  "Candidate regions: motion (segmentation; default) or interest (the "
                  "interest map's parts, e.g. with a position filter)");
  cmd->add_option("--tracker-config", args->tracker_config, "Tracker options (YAML)");
  cmd->add_option("--depth", args->object.depth,
                  "No --model: depth source planesweep, stereo or sensor");
  cmd->add_option("--model-config", args->object.model_config, "No --model: modeller options");
  cmd->add_option("--update", args->update, "No --model: incremental, periodic or none");
  cmd->add_option("--reselect-after", args->reselect_after,
                  "Frames lost in a row before the object is searched for again");
  cmd->add_option("--out", args->out, "Pose stream to write (.csv or .jsonl)");
  cmd->add_option("--overlay", args->overlay,
                  "Overlay video (.mp4/.avi) or PNG folder: interest, regions, model, status");
  cmd->add_flag("--show", args->show, "Show the overlay in a window (q or Esc stops)");
  cmd->add_option("--max-frames", args->max_frames, "Process at most N frames");
  cmd->callback([args] { RunSystem(*args); });
}

}  // namespace

UNSEEN_REGISTER_COMMAND("run", AddRunCommand);

}  // namespace unseen::cli
