// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// End-to-end tracker benchmark: accuracy, lost frames, frames per second (1 and 2 threads)
// and per-stage time on the development sequences and on the SPEC 8 synthetic experiments
// (rendered with the synthesizer from scenes/*.yaml), plus the thesis comparisons: colour
// modes (3.6), model scale error (Table 4.2), the five speeds (Table 4.3), occluders with
// and without rejection (3.4), side light with and without LINF (3.2), and model size; and
// each development sequence with one modality at a time (photometric, silhouette, depth)
// against all of them; and every development and held-out sequence started from a first
// pose off the ground truth (the "start" group); and recordings without ground truth from
// the first pose their init_pose.txt gives (the "real" group: frames tracked and lost).
// Prints a table per group and writes every row to a JSON file.
//
//   tracker_benchmark [--data DIR] [--scenes DIR] [--work DIR] [--json FILE]
//                     [--groups dev,synthetic,...] [--max-frames N] [--config tracker.yaml]
//                     [--heldout DIRS] [--real DIRS]
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "unseen/eval/evaluation.h"
#include "unseen/eval/sequence_poses.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/io/pose_stream.h"
#include "unseen/io/sequence.h"
#include "unseen/mesh/primitives.h"
#include "unseen/select/known_model_pose.h"
#include "unseen/synth/scene.h"
#include "unseen/synth/synthesizer.h"
#include "unseen/system/frame_source.h"
#include "unseen/system/tracking_session.h"
#include "unseen/track/tracker.h"
#include "unseen/util/error.h"
#include "unseen/util/files.h"
#include "unseen/util/logging.h"
#include "unseen/util/memory.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

struct BenchArgs {
  std::string data_dir = std::string(UNSEEN_SOURCE_DIR) + "/../shared/data/sequences";
  std::string scenes_dir = std::string(UNSEEN_SOURCE_DIR) + "/scenes";
  std::string work_dir = "bench_sequences";
  std::string json_path = "tracker_benchmark.json";
  // Folders of sequences kept out of the repository (renders of other objects, lights,
  // cameras; other recordings), comma-separated; default $UNSEEN_HELDOUT_SEQUENCES.
  std::string heldout_dirs;
  // Folders of recordings without ground truth, each sequence with its first pose in
  // init_pose.txt (tx,ty,tz,qx,qy,qz,qw), comma-separated; default $UNSEEN_REAL_SEQUENCES.
  std::string real_dirs;
  std::string groups =
      "dev,heldout,start,real,modalities,synthetic,color,scale,speed,occlusion,linf,model_size,"
      "budget";
  int max_frames = 0;  // 0 = all
  // Tracker options (YAML) every run starts from instead of the defaults, so that a
  // setting can be compared across all groups; empty: the defaults.
  std::string config_path;
};

// One tracking run: a sequence, a model, options, a thread count.
struct Run {
  std::string group;
  std::string name;
  std::string sequence_dir;
  TrackerOptions options;
  std::function<Mesh(const Sequence&)> model;  // default: the sequence's own model
  int threads = 1;
  std::string thesis;  // the thesis's figure for this row, for comparison
  // A first pose off the ground truth (the "start" group): moved start_offset_m in a random
  // direction and turned start_turn_deg about a random axis through the model's origin,
  // both drawn from start_seed; 0: the true first pose.
  double start_offset_m = 0.0;
  double start_turn_deg = 0.0;
  unsigned start_seed = 0;
  // The first pose's file (the "real" group); the run is then scored by the frames it
  // tracked, whether or not the sequence has ground truth.
  std::string init_pose_path = "";
};

// The pose `path` holds (one line tx,ty,tz,qx,qy,qz,qw, metres, world frame).
Rigid3d ReadPoseFile(const std::string& path) {
  std::ifstream in(path);
  UNSEEN_CHECK(in.good(), "{}: cannot read the first pose", path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return ParsePoseText(text, path);
}

// `truth` moved `offset_m` along a random direction and turned `turn_deg` about a random
// axis through the model's origin (world frame), both drawn from `seed`.
Rigid3d OffStart(const Rigid3d& truth, double offset_m, double turn_deg, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  const Eigen::Vector3d direction(normal(rng), normal(rng), normal(rng));
  const Eigen::Vector3d axis(normal(rng), normal(rng), normal(rng));
  return Rigid3d(ExpSO3(axis.normalized() * (turn_deg * M_PI / 180.0)) * truth.rotation(),
                 truth.translation() + direction.normalized() * offset_m);
}

struct RunOutcome {
  // Without ground truth (the "real" group) only its frame counts are filled: frames,
  // scored_frames (returned tracking) and lost_frames.
  EvaluationResult eval;
  bool has_truth = true;
  int frames = 0;
  double fps = 0.0;        // frames / seconds spent in Tracker::Track
  StageTimes mean_times;   // mean per frame
  double mean_pixels = 0;  // mean equations per frame at the finest level
  double mean_renders = 0; // render-solve rounds per frame, all levels
  double mean_levels = 0;  // pyramid levels per frame
  double cpu_ms = 0;       // process CPU time per frame in Tracker::Track (all threads)
  // Median Tracker::Track time of the frames it returned tracked, and of those it returned
  // lost (the re-acquisition searches), frame 0 left out; 0 when there are none.
  double median_tracked_ms = 0, median_lost_ms = 0;
  // Median time of the frames that began lost, so that Track ran a re-acquisition search,
  // whether or not it found the object (one that does is returned tracked); 0 when none.
  double median_search_ms = 0;
  int search_frames = 0;
};

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

RunOutcome Execute(const Run& run, int max_frames) {
  cv::setNumThreads(run.threads);
  const Sequence sequence = Sequence::Open(run.sequence_dir);
  const bool scored_by_truth = run.init_pose_path.empty();
  UNSEEN_CHECK(!scored_by_truth || sequence.has_ground_truth(),
               "{}: the {} group needs ground truth (recordings without it: --real)",
               run.sequence_dir, run.group);
  Mesh model = run.model ? run.model(sequence) : sequence.LoadModel();
  TrackerOptions options = run.options;
  options.threads = run.threads;
  // The predictor's time step is the sequence's frame interval, as `unseen track` sets it
  // (a 10 fps sequence was predicted as if at 30 fps).
  if (sequence.fps() > 0) options.frame_interval_s = 1.0 / sequence.fps();
  Tracker tracker(sequence.rig(), std::move(model), options);
  // As `unseen track` with a model file: a lost object is also tried in its views' turns.
  tracker.SetPoseProposer(ViewBankProposer(&tracker));
  const std::optional<Rigid3d> start =
      scored_by_truth ? sequence.GroundTruth(0) : ReadPoseFile(run.init_pose_path);
  UNSEEN_CHECK(start.has_value(), "{}: frame 0 has no ground truth", run.sequence_dir);
  const bool off = run.start_offset_m > 0.0 || run.start_turn_deg > 0.0;
  const Rigid3d first =
      off ? OffStart(*start, run.start_offset_m, run.start_turn_deg, run.start_seed) : *start;
  if (off) UNSEEN_LOG_INFO("{}: starts at {}", run.name, first.ToString());
  tracker.Initialize(first);

  const int n =
      max_frames > 0 ? std::min(max_frames, sequence.num_frames()) : sequence.num_frames();
  RunOutcome out;
  std::vector<double> tracked_ms, lost_ms, search_ms;
  bool began_lost = false;  // the previous frame was returned lost: this one searches
  SequenceFrameSource source(&sequence);
  SessionOptions session_options;
  session_options.name = run.name;
  session_options.max_frames = n;
  session_options.read_ahead = false;  // the frame is read, then tracked, on one thread
  TrackingSession session(source, session_options);
  const SessionSummary summary = session.Run(
      [&](const Frame& frame) {
        // A frame that cannot be read in full ends the benchmark (Sequence::ReadFrame's error).
        if (!frame.errors.empty()) ThrowError("{}", frame.errors.front().message);
        return SessionStep::FromTrack(tracker.Track(frame));
      },
      [&](const Frame& frame, const SessionStep& step, const SessionFrame&) {
        out.mean_pixels += step.track->summary.equations;
        out.mean_renders += step.track->summary.renders;
        out.mean_levels += step.track->summary.num_levels;
        if (frame.frame_id > 0) {
          (step.track->status == TrackStatus::kTracking ? tracked_ms : lost_ms)
              .push_back(step.track->summary.times.total_ms);
          if (began_lost) search_ms.push_back(step.track->summary.times.total_ms);
        }
        began_lost = step.track->status != TrackStatus::kTracking;
        return true;
      });
  out.median_tracked_ms = Median(tracked_ms);
  out.median_lost_ms = Median(lost_ms);
  out.median_search_ms = Median(search_ms);
  out.search_frames = static_cast<int>(search_ms.size());
  const std::vector<PoseRecord>& poses = summary.records;
  if (scored_by_truth) {
    std::vector<GroundTruthFrame> truth = SequenceGroundTruth(sequence);
    truth.resize(std::min<size_t>(truth.size(), n));
    out.eval = Evaluate(truth, poses);
  } else {
    out.has_truth = false;
    out.eval.frames = static_cast<int>(poses.size());
    for (const PoseRecord& p : poses) {
      (p.status == TrackStatus::kTracking ? out.eval.scored_frames : out.eval.lost_frames)++;
    }
  }
  out.frames = n;
  out.fps = summary.fps();
  const double k = n > 0 ? 1.0 / n : 0.0;
  out.mean_times = summary.stage_times;
  StageTimes& t = out.mean_times;
  t.predict_ms *= k;
  t.render_ms *= k;
  t.preprocess_ms *= k;
  t.select_ms *= k;
  t.solve_ms *= k;
  t.total_ms *= k;
  out.mean_pixels *= k;
  out.mean_renders *= k;
  out.mean_levels *= k;
  out.cpu_ms = summary.cpu_ms * k;
  return out;
}

nlohmann::json ToJson(const Run& run, const RunOutcome& o) {
  nlohmann::json j = o.eval.ToJson();
  if (!o.has_truth) {
    // Nothing to score the poses against: the frames returned tracking and lost only.
    for (auto& [key, value] : j.items()) {
      if (key.find("_err_") != std::string::npos || key == "success_5cm5deg" ||
          key == "success_2cm2deg" || key == "first_failure_frame") {
        value = nullptr;
      }
    }
    j["ground_truth"] = false;
    j["init_pose"] = run.init_pose_path;
  }
  j["group"] = run.group;
  j["name"] = run.name;
  j["sequence"] = fs::path(run.sequence_dir).filename().string();
  j["threads"] = run.threads;
  j["frames_tracked"] = o.frames;
  j["fps_track_only"] = o.fps;
  j["mean_equations"] = o.mean_pixels;
  j["mean_renders"] = o.mean_renders;
  j["mean_levels"] = o.mean_levels;
  j["cpu_ms_per_frame"] = o.cpu_ms;
  j["median_ms_tracked_frame"] = o.median_tracked_ms;
  j["median_ms_lost_frame"] = o.median_lost_ms;
  // What a lost frame's search costs against a tracked frame (the goal: at most 3x).
  j["lost_frame_cost_ratio"] = o.median_tracked_ms > 0.0 && o.median_lost_ms > 0.0
                                   ? nlohmann::json(o.median_lost_ms / o.median_tracked_ms)
                                   : nlohmann::json(nullptr);
  j["search_frames"] = o.search_frames;
  j["median_ms_search_frame"] = o.median_search_ms;
  // The same for the frames that ran a search, including those that found the object.
  j["search_frame_cost_ratio"] = o.median_tracked_ms > 0.0 && o.median_search_ms > 0.0
                                     ? nlohmann::json(o.median_search_ms / o.median_tracked_ms)
                                     : nlohmann::json(nullptr);
  j["stage_ms"] = {{"predict", o.mean_times.predict_ms},   {"render", o.mean_times.render_ms},
                   {"preprocess", o.mean_times.preprocess_ms},
                   {"select", o.mean_times.select_ms}, {"solve", o.mean_times.solve_ms},
                   {"total", o.mean_times.total_ms}};
  j["thesis"] = run.thesis;
  return j;
}

std::string Row(const Run& run, const RunOutcome& o) {
  const EvaluationResult& e = o.eval;
  const bool any = o.has_truth && e.scored_frames > 0;
  auto percent = [&](double share) {
    return o.has_truth ? fmt::format("{:.1f}%", 100.0 * share) : std::string("-");
  };
  return fmt::format(
      "{:<34} {:>2} {:>6} {:>6} {:>4} {:>7} {:>7} {:>7} {:>6} {:>6} {:>7.0f} {:>5.2f} "
      "{:>4.1f} {:>5.2f} {:>5.2f} {:>5.2f}  {}",
      run.name, run.threads, percent(e.success_rate), percent(e.strict_success_rate), e.lost_frames,
      any ? fmt::format("{:.2f}", e.trans_err_mm.mean) : "-",
      any ? fmt::format("{:.2f}", e.trans_err_mm.rms) : "-",
      any ? fmt::format("{:.1f}", e.trans_err_mm.max) : "-",
      any ? fmt::format("{:.2f}", e.rot_err_deg.mean) : "-",
      any ? fmt::format("{:.2f}", e.rot_err_deg.max) : "-", o.fps, o.cpu_ms, o.mean_renders,
      o.mean_times.render_ms, o.mean_times.preprocess_ms + o.mean_times.select_ms,
      o.mean_times.solve_ms, run.thesis);
}

std::string Header() {
  return fmt::format(
      "{:<34} {:>2} {:>6} {:>6} {:>4} {:>7} {:>7} {:>7} {:>6} {:>6} {:>7} {:>5} {:>4} {:>5} {:>5} "
      "{:>5}  {}",
      "run", "th", "5cm5°", "2cm2°", "lost", "mean_mm", "rms_mm", "max_mm", "mean°", "max°", "fps", "cpu",
      "rnd", "rend", "sel", "solve", "thesis");
}

// Renders scenes/<name>.yaml into work/<name> unless it is there and newer than the scene.
std::string SyntheticSequence(const BenchArgs& args, const std::string& name) {
  const fs::path scene = fs::path(args.scenes_dir) / (name + ".yaml");
  UNSEEN_CHECK(fs::exists(scene), "{}: scene file not found", scene.string());
  const fs::path out = fs::path(args.work_dir) / name;
  const fs::path marker = out / "sequence.json";
  if (!fs::exists(marker) || fs::last_write_time(marker) < fs::last_write_time(scene)) {
    UNSEEN_LOG_INFO("rendering {} into {}", scene.string(), out.string());
    SynthOptions options;
    options.progress = false;
    Synthesize(LoadScene(scene.string()), out.string(), options);
  }
  return out.string();
}

// The sequence folders of `data_dir`, sorted.
std::vector<fs::path> DevSequences(const std::string& data_dir) {
  std::vector<fs::path> dirs;
  for (const auto& entry : fs::directory_iterator(data_dir)) {
    if (entry.is_directory() && fs::exists(entry.path() / "sequence.json")) {
      dirs.push_back(entry.path());
    }
  }
  std::sort(dirs.begin(), dirs.end());
  return dirs;
}

// The sequence folders inside the comma-separated folders of `list` (default: the
// environment variable `env`), each folder's sorted; a folder not found is skipped.
std::vector<fs::path> SequenceFolders(std::string list, const char* env) {
  if (list.empty() && std::getenv(env)) list = std::getenv(env);
  std::vector<fs::path> dirs;
  for (size_t start = 0; start < list.size();) {
    const size_t end = std::min(list.find(',', start), list.size());
    const fs::path folder = list.substr(start, end - start);
    start = end + 1;
    if (folder.empty()) continue;
    if (!IsFolder(folder)) {
      UNSEEN_LOG_WARN("sequence folder {} not found: skipped", folder.string());
      continue;
    }
    for (const fs::path& dir : DevSequences(folder.string())) dirs.push_back(dir);
  }
  return dirs;
}

std::vector<Run> PlanRuns(const BenchArgs& args, const std::vector<std::string>& groups) {
  auto wanted = [&](const std::string& g) {
    return std::find(groups.begin(), groups.end(), g) != groups.end();
  };
  const bool have_dev = fs::exists(args.data_dir);
  if (!have_dev) UNSEEN_LOG_WARN("{} not found: development sequences skipped", args.data_dir);
  std::vector<Run> runs;
  auto add = [&](Run run) { runs.push_back(std::move(run)); };
  const TrackerOptions defaults =
      args.config_path.empty() ? TrackerOptions() : LoadTrackerOptions(args.config_path);

  if (wanted("dev") && have_dev) {
    for (const fs::path& dir : DevSequences(args.data_dir)) {
      // What to compare with: the thesis's figure for its synthetic protocol, the measured
      // peer tracker's on the real RGB-D footage, nothing for other recordings.
      const std::string name = dir.filename().string();
      std::string reference;
      if (name == "visp_rbt_cube") {
        reference = "peer (region-based, RGB-D): 100 %, 10.6 mm, 2.1°";
      } else if (fs::exists(dir / "scene.json") || name.rfind("cube_", 0) == 0 ||
                 name.rfind("box_", 0) == 0 || name.rfind("sphere_", 0) == 0 ||
                 name.rfind("rig5_", 0) == 0) {
        reference = "~5 mm, 0.5° (exact model, synthetic)";
      }
      for (int threads : {1, 2}) {
        add({"dev", name, dir.string(), defaults, {}, threads, reference});
      }
      // An RGB-D recording also without its depth (a colour camera alone): the real cube
      // so tracked is the case the appearance-change rules must not lose.
      if (Sequence::Open(dir.string()).has_depth()) {
        TrackerOptions colour_only = defaults;
        colour_only.depth.enabled = false;
        add({"dev", name + " colour only", dir.string(), colour_only, {}, 1,
             name == "visp_rbt_cube" ? "peer (region-based, colour only): 88 %, 11.7 mm, 3.2°"
                                     : reference});
      }
    }
  }
  // Sequences the tracker was not tuned on (--heldout folders).
  auto heldout_sequences = [&]() {
    return SequenceFolders(args.heldout_dirs, "UNSEEN_HELDOUT_SEQUENCES");
  };
  if (wanted("heldout")) {
    // Defaults, one thread, from the true first pose.
    for (const fs::path& dir : heldout_sequences()) {
      add({"heldout", dir.filename().string(), dir.string(), defaults, {}, 1, ""});
    }
  }
  if (wanted("real")) {
    // Recordings without ground truth, from the first pose their init_pose.txt gives,
    // defaults, one thread: tracked and lost frames (ViSP's real footage,
    // bench/heldout/visp_*.py).
    for (const fs::path& dir : SequenceFolders(args.real_dirs, "UNSEEN_REAL_SEQUENCES")) {
      const fs::path init = dir / "init_pose.txt";
      if (!IsFile(init)) {
        UNSEEN_LOG_WARN("{}: no init_pose.txt: skipped by the real group", dir.string());
        continue;
      }
      Run run{"real", dir.filename().string(), dir.string(), defaults, {}, 1, ""};
      run.init_pose_path = init.string();
      add(std::move(run));
    }
  }
  if (wanted("start")) {
    // Every development and held-out sequence from a first pose 8 mm and 4 degrees off the
    // ground truth, three draws of the direction and axis.
    std::vector<fs::path> dirs = have_dev ? DevSequences(args.data_dir) : std::vector<fs::path>();
    for (const fs::path& dir : heldout_sequences()) dirs.push_back(dir);
    for (const fs::path& dir : dirs) {
      for (unsigned seed : {1u, 2u, 3u}) {
        add({"start", fmt::format("{} 8mm/4° #{}", dir.filename().string(), seed), dir.string(),
             defaults, {}, 1, "", 0.008, 4.0, seed});
      }
    }
  }
  if (wanted("modalities") && have_dev) {
    // One modality at a time against all of them (the defaults), on every development
    // sequence; depth only where the frames carry it.
    for (const fs::path& dir : DevSequences(args.data_dir)) {
      const bool has_depth = Sequence::Open(dir.string()).has_depth();
      const std::string name = dir.filename().string();
      TrackerOptions photometric = defaults;
      photometric.photometric.require_appearance = false;
      photometric.region.enabled = false;
      photometric.depth.enabled = false;
      TrackerOptions silhouette = defaults;
      silhouette.photometric.enabled = false;
      silhouette.depth.enabled = false;
      TrackerOptions depth = defaults;
      depth.photometric.enabled = false;
      depth.region.enabled = false;
      add({"modalities", name + " photometric", dir.string(), photometric, {}, 1, ""});
      add({"modalities", name + " silhouette", dir.string(), silhouette, {}, 1, ""});
      if (has_depth) add({"modalities", name + " depth", dir.string(), depth, {}, 1, ""});
      add({"modalities", name + " all", dir.string(), defaults, {}, 1, ""});
    }
  }
  if (wanted("synthetic")) {
    for (const char* name : {"cube_diffuse", "cube_sidelight", "cube_lowlight", "cube_clutter",
                             "globe_spin", "box_textured", "rig5_fig312"}) {
      add({"synthetic", name, SyntheticSequence(args, name), defaults, {}, 1,
           "~5 mm, 0.5°; globe 0.9°"});
    }
  }
  if (wanted("color")) {
    const std::string seq = SyntheticSequence(args, "cube_clutter");
    for (ColorMode mode : {ColorMode::kColorGradientRedundancy, ColorMode::kRawColor,
                           ColorMode::kGrey}) {
      TrackerOptions o = defaults;
      o.selection.color_mode = mode;
      add({"color", fmt::format("cube_clutter {}", ToString(mode)), seq, o, {}, 1,
           mode == ColorMode::kColorGradientRedundancy ? "5x faster than raw, equal accuracy"
                                                       : ""});
    }
  }
  if (wanted("scale")) {
    const std::string seq = SyntheticSequence(args, "cube_diffuse");
    for (double error : {0.0, 0.1, 0.2, 0.25, 0.3, 0.4}) {
      add({"scale", fmt::format("cube_diffuse model x{:.2f}", 1.0 + error), seq, defaults,
           [error](const Sequence& s) {
             Mesh m = s.LoadModel();
             m.Scale(static_cast<float>(1.0 + error));
             return m;
           },
           1, error <= 0.22 ? "tracked (up to 22 %)" : "lost (at 25 %)"});
    }
  }
  if (wanted("speed")) {
    const std::vector<std::pair<const char*, const char*>> speeds = {
        {"speed_030_015", "tracked"},
        {"speed_060_030", "tracked"},
        {"speed_120_060", "tracked reliably"},
        {"speed_240_120", "lost at the 2nd turn"},
        {"speed_480_240", "lost at once"}};
    for (const auto& [name, thesis] : speeds) {
      add({"speed", name, SyntheticSequence(args, name), defaults, {}, 1, thesis});
    }
  }
  if (wanted("budget")) {
    // The pixel budget of the finest level (pyramid.max_finest_px) against level 0 always.
    const std::string seq = SyntheticSequence(args, "box_closeup");
    TrackerOptions level0 = defaults;
    level0.pyramid.max_finest_px = 0.0;
    add({"budget", "box_closeup budget", seq, defaults, {}, 1, ""});
    add({"budget", "box_closeup level 0", seq, level0, {}, 1, ""});
  }
  if (wanted("occlusion")) {
    std::vector<std::pair<std::string, std::string>> seqs = {
        {"occluder_white_bar", SyntheticSequence(args, "occluder_white_bar")},
        {"occluder_cube", SyntheticSequence(args, "occluder_cube")}};
    if (have_dev) seqs.emplace_back("box_occluded_bar", args.data_dir + "/box_occluded_bar");
    for (const auto& [name, seq] : seqs) {
      for (bool reject : {true, false}) {
        TrackerOptions o = defaults;
        o.selection.use_occlusion_rejection = reject;
        add({"occlusion", fmt::format("{} rejection {}", name, reject ? "on" : "off"), seq, o,
             {}, 1, reject ? "~10 mm, 2.5°" : "lost"});
      }
    }
  }
  if (wanted("linf")) {
    std::vector<std::pair<std::string, std::string>> seqs = {
        {"cube_sidelight", SyntheticSequence(args, "cube_sidelight")}};
    if (have_dev) {
      seqs.emplace_back("cube_clutter_sidelight", args.data_dir + "/cube_clutter_sidelight");
    }
    for (const auto& [name, seq] : seqs) {
      for (bool linf : {true, false}) {
        TrackerOptions o = defaults;
        o.preprocess.use_linf = linf;
        add({"linf", fmt::format("{} LINF {}", name, linf ? "on" : "off"), seq, o, {}, 1,
             linf ? "tracked" : "diverged"});
      }
    }
  }
  if (wanted("model_size")) {
    const std::string seq = SyntheticSequence(args, "globe_spin");
    // The globe of the scene (25 x 50 quads, ~2 400 triangles) against the same sphere and
    // texture tessellated into ~100 000 triangles.
    const Scene scene = LoadScene(args.scenes_dir + "/globe_spin.yaml");
    for (const auto& [rings, segments] : {std::pair{25, 50}, std::pair{224, 224}}) {
      ObjectSpec spec = scene.object;
      spec.rings = rings;
      spec.segments = segments;
      const Mesh mesh = BuildObjectMesh(spec);
      add({"model_size", fmt::format("globe_spin {} triangles", mesh.num_triangles()), seq,
           defaults, [mesh](const Sequence&) { return mesh; }, 1,
           segments == 50 ? "80-100 fps (GPU)" : "71-91 fps (GPU)"});
    }
  }
  return runs;
}

int Main(int argc, char** argv) {
  BenchArgs args;
  CLI::App app{"unseen tracker benchmark: accuracy and speed on the development sequences, "
               "the SPEC 8 experiments and the thesis comparisons"};
  app.add_option("--data", args.data_dir, "Development sequences folder");
  app.add_option("--scenes", args.scenes_dir, "Scene files (scenes/*.yaml)");
  app.add_option("--work", args.work_dir, "Where synthetic sequences are rendered and cached");
  app.add_option("--json", args.json_path, "Results JSON to write");
  app.add_option("--heldout", args.heldout_dirs,
                 "Comma-separated folders of held-out sequences (default: "
                 "$UNSEEN_HELDOUT_SEQUENCES); the heldout group runs each sequence in them");
  app.add_option("--real", args.real_dirs,
                 "Comma-separated folders of recordings without ground truth, each sequence "
                 "with its first pose in init_pose.txt (default: $UNSEEN_REAL_SEQUENCES); the "
                 "real group tracks each and counts the frames tracked and lost");
  app.add_option("--groups", args.groups,
                 "Comma-separated: dev,heldout,start,real,modalities,synthetic,color,scale,speed,"
                 "occlusion,linf,model_size,budget (start: every development and held-out "
                 "sequence from a first pose 8 mm and 4 degrees off, three draws)");
  app.add_option("--max-frames", args.max_frames, "Track at most N frames per run (0 = all)");
  app.add_option("--config", args.config_path,
                 "Tracker options (YAML) every run starts from (default: the built-in defaults)");
  CLI11_PARSE(app, argc, argv);
  SetVerbosity(1);

  std::vector<std::string> groups;
  for (size_t start = 0; start <= args.groups.size();) {
    const size_t end = std::min(args.groups.find(',', start), args.groups.size());
    if (end > start) groups.push_back(args.groups.substr(start, end - start));
    start = end + 1;
  }
  fs::create_directories(args.work_dir);
  const std::vector<Run> runs = PlanRuns(args, groups);

  nlohmann::json rows = nlohmann::json::array();
  std::string current_group;
  for (const Run& run : runs) {
    if (run.group != current_group) {
      current_group = run.group;
      std::printf("\n== %s\n%s\n", current_group.c_str(), Header().c_str());
    }
    const RunOutcome outcome = Execute(run, args.max_frames);
    std::printf("%s\n", Row(run, outcome).c_str());
    std::fflush(stdout);
    rows.push_back(ToJson(run, outcome));
  }
  nlohmann::json doc = {{"benchmark", "tracker"},
                        {"hardware_threads", static_cast<int>(std::thread::hardware_concurrency())},
                        {"runs", rows}};
  std::ofstream out(args.json_path);
  UNSEEN_CHECK(out.good(), "{}: cannot write the results", args.json_path);
  out << doc.dump(1) << "\n";
  std::printf("\nResults: %s\n", args.json_path.c_str());
  return 0;
}

}  // namespace
}  // namespace unseen

int main(int argc, char** argv) {
  unseen::KeepFreedMemoryForReuse();
  try {
    return unseen::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tracker_benchmark: error: %s\n", e.what());
    return 1;
  }
}
