// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// `unseen track SEQ --init gt|auto|POSE`: tracks the sequence's object (or --model) through
// every frame with the 6-DoF tracker (from the true pose, from the pose found in the object's
// box or selected region, or from the pose given), writes the pose stream, a statistics JSON and
// optionally an overlay video, and prints a summary (fps, lost frames, error against ground truth).
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tools/unseen/commands.h"
#include "tools/unseen/known_object.h"
#include "tools/unseen/unknown_object.h"
#include "unseen/eval/overlay.h"
#include "unseen/io/pose_stream.h"
#include "unseen/io/sequence.h"
#include "unseen/mesh/mesh_io.h"
#include "unseen/model/model_updater.h"
#include "unseen/model/modeller.h"
#include "unseen/select/known_model_pose.h"
#include "unseen/system/frame_source.h"
#include "unseen/system/tracking_session.h"
#include "unseen/track/tracker.h"
#include "unseen/util/error.h"
#include "unseen/util/files.h"
#include "unseen/util/logging.h"
#include "unseen/util/progress.h"

namespace unseen::cli {
namespace {

struct TrackArgs {
  int obj_id = 0;  // --obj-id; 0: the sequence's own object
  std::string sequence;
  std::string model;
  std::string model_units = "mm";
  double model_scale = 1.0;
  std::string init;
  std::string filters;  // --init auto: interest filter bank (YAML)
  std::string config;
  std::string cameras;
  std::string out;
  std::string stats;
  std::string overlay;
  int first_frame = 0;
  int max_frames = 0;
  int threads = -1;  // -1: as the options say
  // --unknown: no model file; the modeller builds one from the first frame and keeps it
  // current (SPEC 5).
  bool unknown = false;
  UnknownObjectArgs object;  // --roi, --mask, --depth, --model-config (init: --init)
  std::string update = "incremental";
  int update_frames = 30;
  double update_refresh = ModelUpdateOptions().refresh_confidence;
  bool update_in_frame = false;
  std::string save_model;
};

std::vector<std::string> SplitComma(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

void RunTrack(const TrackArgs& args) {
  namespace fs = std::filesystem;
  UNSEEN_CHECK(Exists(args.sequence), "track: sequence '{}' does not exist", args.sequence);
  UNSEEN_CHECK(std::isfinite(args.model_scale) && args.model_scale > 0.0,
               "track: --model-scale {} must be > 0", args.model_scale);
  UNSEEN_CHECK(args.model_units == "mm" || args.model_units == "m",
               "track: --model-units '{}' must be mm or m", args.model_units);
  Sequence sequence = Sequence::Open(args.sequence, args.obj_id);
  const std::string reference_name = sequence.rig().cameras.at(sequence.reference_camera()).name;
  if (!args.cameras.empty()) sequence.SelectCameras(SplitComma(args.cameras));
  TrackerOptions options =
      args.config.empty() ? TrackerOptions() : LoadTrackerOptions(args.config);
  if (args.threads >= 0) {
    options.threads = args.threads;
    options.Check();
  }

  Mesh model;
  std::unique_ptr<Modeller> modeller;
  std::unique_ptr<ModelUpdater> updater;
  UNSEEN_CHECK(args.first_frame >= 0 && args.first_frame < sequence.num_frames(),
               "track: --first-frame {} is outside [0, {})", args.first_frame,
               sequence.num_frames());
  std::optional<Rigid3d> unknown_start;
  if (args.unknown) {
    UNSEEN_CHECK(args.model.empty(), "track: --unknown and --model exclude each other");
    UnknownObjectArgs object = args.object;
    object.init = args.init;
    const ModellerOptions model_options = ModellerOptionsFor(object, sequence, "track");
    int reference = sequence.rig().Find(reference_name);
    UNSEEN_CHECK(reference >= 0,
                 "track: --cameras leaves out the reference camera '{}' the "
                 "model is built from",
                 reference_name);
    modeller = std::make_unique<Modeller>(sequence.rig(), reference, model_options);
    const Frame first = sequence.ReadFrame(args.first_frame);
    const ObjectStart start =
        LocateUnknownObject(object, sequence, args.first_frame, first, *modeller, "track");
    const ModelBuild build = modeller->Build(first, start.world_from_obj, start.region, start.mask);
    UNSEEN_CHECK(build.ok(), "track: cannot model the object in the first frame: {}", build.why);
    UNSEEN_LOG_INFO("track: on-line model from frame {}: {} triangles ({}, {:.1f} ms)",
                    first.frame_id, build.mesh->num_triangles(),
                    ToString(model_options.depth.source), build.depth_ms + build.mesh_ms);
    unknown_start = start.world_from_obj;
    ModelUpdateOptions update;
    try {
      update.mode = ParseModelUpdateMode(args.update);
    } catch (const Error& e) {
      ThrowError("track: --update: {}", e.what());
    }
    update.every_frames = args.update_frames;
    update.refresh_confidence = args.update_refresh;
    update.asynchronous = !args.update_in_frame;
    try {
      update.Check();
    } catch (const Error& e) {
      ThrowError("track: --update-frames, --update-refresh: {}", e.what());
    }
    updater = std::make_unique<ModelUpdater>(modeller.get(), update);
    model = updater->Start(build);
  } else if (args.model.empty()) {
    UNSEEN_CHECK(!sequence.model_path().empty(),
                 "track: sequence '{}' has no model of object {} (no models/obj_{:06d}.ply|obj|"
                 "gltf|glb); give one with --model, or another object with --obj-id",
                 args.sequence, sequence.obj_id(), sequence.obj_id());
    model = sequence.LoadModel();
  } else {
    model = LoadMesh(args.model, args.model_units == "mm" ? 0.001 : 1.0);
  }
  if (args.model_scale != 1.0) model.Scale(static_cast<float>(args.model_scale));

  Rigid3d initial;
  UNSEEN_CHECK(unknown_start || !args.init.empty(),
               "track: --init is required (gt, auto, or tx,ty,tz,qx,qy,qz,qw)");
  const bool auto_init = !unknown_start && args.init == "auto";
  UNSEEN_CHECK(args.filters.empty() || (auto_init && args.object.roi.empty()),
               "track: --filters serves --init auto without --roi only");
  UNSEEN_CHECK(args.object.roi.empty() || args.unknown || auto_init,
               "track: --roi serves --unknown or --init auto only");
  if (unknown_start) {
    initial = *unknown_start;
  } else if (args.init == "gt") {
    const std::optional<Rigid3d> gt = sequence.GroundTruth(args.first_frame);
    UNSEEN_CHECK(gt.has_value(), "track: --init gt but sequence '{}' has no ground truth for "
                 "its first frame", args.sequence);
    initial = *gt;
  } else if (!auto_init) {
    initial = ParsePoseText(args.init, "track: --init (gt, auto or tx,ty,tz,qx,qy,qz,qw)");
  }

  TrackerOptions tracker_options = options;
  // The predictor's time step is the sequence's frame interval.
  if (sequence.fps() > 0) tracker_options.frame_interval_s = 1.0 / sequence.fps();
  Tracker tracker(sequence.rig(), std::move(model), tracker_options);
  // A known model: a lost object found again by correlation is also tried in the
  // orientations its views match there (an on-line model changes, its views would not).
  if (!args.unknown) {
    tracker.SetPoseProposer(ViewBankProposer(&tracker, {}, ViewBankBuild::kInBackground));
  }
  // --init auto: the first frame is the one where the model was found (its result is the
  // search's; the tracker starts at that pose with the next frame).
  std::optional<KnownObjectStart> found;
  int start_index = args.first_frame;
  if (auto_init) {
    found = FindKnownObject(sequence, args.first_frame, args.object.roi, args.filters, &tracker,
                            "track");
    start_index = found->index;
  } else {
    tracker.Initialize(initial);
  }

  const int available = sequence.num_frames() - start_index;
  const int frames = args.max_frames > 0 ? std::min(args.max_frames, available) : available;
  SequenceFrameSource source(&sequence, start_index,
                             found ? std::optional<Frame>(found->frame) : std::nullopt);
  SessionOptions session_options;
  session_options.name = "track";
  session_options.max_frames = frames;
  session_options.poses_file = args.out;
  TrackingSession session(source, session_options);
  // Frames done, fps and ETA on stderr, when it is a terminal (logs stay clean).
  ProgressLine progress("track", frames, isatty(fileno(stderr)) != 0);
  // An image that cannot be read (a dropped frame, a damaged file) is a warning: its camera
  // sits the frame out, and a frame without any image is reported lost with the held pose
  // (Tracker::Track, SkipFrame).
  int unreadable = 0;  // frames with a colour image that could not be read
  bool first = true;
  const SessionSummary summary = session.Run(
      [&](const Frame& frame) {
        const bool any_image = std::any_of(frame.images.begin(), frame.images.end(),
                                           [](const cv::Mat& im) { return !im.empty(); });
        bool image_missing = false;
        for (const FrameReadError& e : frame.errors) {
          image_missing = image_missing || !e.depth;
          const char* consequence = e.depth     ? "depth skipped"
                                    : any_image ? "tracked with the other cameras"
                                                : "frame reported lost, pose held";
          UNSEEN_LOG_WARN("track: frame {}: camera {}: {}; {}", frame.frame_id,
                          sequence.rig().cameras[e.camera].name, e.message, consequence);
        }
        if (image_missing) ++unreadable;
        // The frame where the model was found took the search.
        if (std::exchange(first, false) && found) {
          return SessionStep::FromTrack(found->pose.tracked,
                                        found->pose.match_ms + found->pose.align_ms);
        }
        const TrackResult r = tracker.Track(frame);
        // A model built beside the tracking takes over at this frame boundary.
        if (updater) updater->AfterTracked(frame, r, &tracker);
        return SessionStep::FromTrack(r);
      },
      [&](const Frame& frame, const SessionStep& step, const SessionFrame& seen) {
        const std::string error_text =
            seen.error ? fmt::format(" err {:.2f} mm {:.3f} deg", 1e3 * seen.error->translation,
                                     seen.error->rotation_rad * 180.0 / M_PI)
                       : std::string();
        UNSEEN_LOG_DEBUG("frame {}:{} {}", frame.frame_id, error_text, step.track->BriefReport());
        progress.Update(seen.index + 1);
        return true;
      });
  progress.Finish();

  const int ncam = sequence.rig().size();
  const int lost = summary.frames - summary.tracking;
  std::printf("track %s: %d frames, %d camera(s), %.1f fps (%.3f ms/frame), %d lost\n",
              args.sequence.c_str(), summary.frames, ncam, summary.fps(), summary.mean_ms(), lost);
  const double n = std::max(summary.frames, 1);
  const StageTimes& sum_times = summary.stage_times;
  std::printf("  mean ms: predict %.3f render %.3f preprocess %.3f select %.3f solve %.3f\n",
              sum_times.predict_ms / n, sum_times.render_ms / n, sum_times.preprocess_ms / n,
              sum_times.select_ms / n, sum_times.solve_ms / n);
  if (updater) {
    const ModelUpdateStats& u = updater->stats();
    std::printf(
        "  on-line model: %d builds started, %d swapped in (%d aligned to the model in "
        "use, mean correction %.1f mm), %d could not model (%.1f ms per build)\n",
        u.started, u.swapped, u.aligned, u.aligned ? u.correction_mm / u.aligned : 0.0, u.failed,
        u.built + u.failed > 0 ? u.build_ms / (u.built + u.failed) : 0.0);
    if (u.fusion.fused > 0) {
      std::printf(
          "  fused model: %d depth maps in %.1f mm voxels, %d key views, %d triangles "
          "(last fusion %.1f ms)\n",
          u.fusion.fused, u.fusion.voxel_mm, u.fusion.key_views, u.fusion.triangles,
          u.fusion.fuse_ms);
    }
  }
  if (!args.save_model.empty()) {
    SaveMesh(tracker.given_model(), args.save_model, 1000.0);
    std::printf("  model in use saved to %s (mm)\n", args.save_model.c_str());
  }
  if (unreadable > 0) {
    std::printf("  %d frame(s) with an unreadable image (see the warnings)\n", unreadable);
  }
  const SessionErrors& e = summary.given;
  if (e.frames > 0) {
    std::printf(
        "  error vs ground truth (%d frames): translation mean %.2f mm max %.2f mm, "
        "rotation mean %.3f deg max %.3f deg\n",
        e.frames, e.mean_mm(), e.max_mm, e.mean_deg(), e.max_deg);
  }
  if (!args.stats.empty()) {
    nlohmann::json j;
    j["sequence"] = args.sequence;
    j["frames"] = summary.frames;
    j["cameras"] = ncam;
    j["fps"] = summary.fps();
    j["lost_frames"] = lost;
    j["unreadable_frames"] = unreadable;
    j["mean_ms"] = {
        {"predict", sum_times.predict_ms / n},       {"render", sum_times.render_ms / n},
        {"preprocess", sum_times.preprocess_ms / n}, {"select", sum_times.select_ms / n},
        {"solve", sum_times.solve_ms / n},           {"total", summary.process_ms / n}};
    if (e.frames > 0) {
      j["translation_error_mm"] = {{"mean", e.mean_mm()}, {"max", e.max_mm}};
      j["rotation_error_deg"] = {{"mean", e.mean_deg()}, {"max", e.max_deg}};
    }
    std::ofstream out(args.stats);
    UNSEEN_CHECK(out.good(), "track: cannot write stats file '{}'", args.stats);
    out << j.dump(2) << "\n";
  }
  if (!args.overlay.empty()) {
    int camera = sequence.rig().Find(reference_name);
    if (camera < 0) camera = 0;
    WriteOverlay(sequence, summary.records, camera, args.overlay);
  }
}

void AddTrackCommand(CLI::App& app) {
  auto args = std::make_shared<TrackArgs>();
  CLI::App* cmd = app.add_subcommand(
      "track", "Track the object of a sequence in 6 DoF from an initial pose; write the poses");
  cmd->add_option("SEQ", args->sequence, "Sequence folder")->required();
  AddObjectIdOption(cmd, &args->obj_id);
  cmd->add_option("--model", args->model, "Model file (default: the sequence's model)");
  cmd->add_option("--model-units", args->model_units, "Units of --model: mm (BOP) or m");
  cmd->add_option("--model-scale", args->model_scale, "Scale the model by this factor");
  cmd->add_flag("--unknown", args->unknown,
                "No model file: build the model on-line from the frames (--init gt, --roi or "
                "--mask says where the object is)");
  cmd->add_option("--roi", args->object.roi,
                  "--unknown or --init auto: object region x,y,w,h (reference image)");
  cmd->add_option("--mask", args->object.mask, "--unknown: object mask image (non-zero = object)");
  cmd->add_option("--depth", args->object.depth,
                  "--unknown: depth source planesweep, stereo or sensor (default: sensor with "
                  "depth images, else stereo for two cameras, else planesweep)");
  cmd->add_option("--model-config", args->object.model_config,
                  "--unknown: modeller options (YAML)");
  cmd->add_option("--update", args->update,
                  "--unknown: model update: incremental (fuse a build every --update-frames into "
                  "one growing model; default), periodic (rebuild every --update-frames, the "
                  "thesis's) or none");
  cmd->add_option("--update-frames", args->update_frames,
                  "--unknown: frames between model rebuilds");
  cmd->add_option("--update-refresh", args->update_refresh,
                  fmt::format("--unknown: rebuild sooner (after {} frames) once a frame's "
                              "confidence falls below this (0: every --update-frames only)",
                              ModelUpdateOptions().refresh_frames));
  cmd->add_flag("--update-in-frame", args->update_in_frame,
                "--unknown: build each new model within its frame instead of beside the "
                "tracking (reproducible runs; the frame's time includes the build)");
  cmd->add_option("--save-model", args->save_model,
                  "Write the model in use at the end (.ply/.obj, millimetres)");
  cmd->add_option("--init", args->init,
                  "Initial pose: 'gt' (first frame's ground truth), 'auto' (found from the "
                  "model's views in --roi, or in the region the interest filters select) or "
                  "tx,ty,tz,qx,qy,qz,qw (metres, world frame); required but with --unknown "
                  "--roi/--mask");
  cmd->add_option("--filters", args->filters,
                  "--init auto without --roi: interest filter bank (YAML; default: motion)");
  cmd->add_option("--config", args->config, "Tracker options (YAML)");
  cmd->add_option("--cameras", args->cameras, "Comma-separated cameras to use (default: all)");
  cmd->add_option("--out", args->out, "Pose stream to write (.csv or .jsonl)");
  cmd->add_option("--stats", args->stats, "Statistics JSON to write (fps, mean per-stage ms)");
  cmd->add_option("--overlay", args->overlay, "Overlay video (.mp4/.avi) or PNG folder");
  cmd->add_option("--first-frame", args->first_frame,
                  "Start at this frame index (--init gt takes its ground truth)");
  cmd->add_option("--max-frames", args->max_frames, "Track at most N frames");
  cmd->add_option("--threads", args->threads,
                  "Threads per frame (overrides the options' 'threads'; 0 = all cores)");
  cmd->callback([args] { RunTrack(*args); });
}

}  // namespace

UNSEEN_REGISTER_COMMAND("track", AddTrackCommand);

}  // namespace unseen::cli
