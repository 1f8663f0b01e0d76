// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Initial pose of a known model, automatically (select/known_model_pose.h, SPEC 4.5): for
// every --every-th frame of each sequence, the pose is found from the model's silhouette
// box at the true pose in the reference camera (what a perfect selection gives; the
// selection has its own figures) and scored against the ground truth: success within
// 5 cm / 5° after the tracker's refinement (the tracking criterion), "no pose" answers,
// wrong poses reported as found, and the time. Prints a table; writes JSON with --json.
//
//   build/bench/initial_pose_benchmark [--every 10] [--extra DIR,...] [--json out.json]
#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "bench_sequences.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/io/sequence.h"
#include "unseen/select/known_model_pose.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/timer.h"
#include "unseen/util/memory.h"

namespace {

using namespace unseen;
namespace fs = std::filesystem;

struct Args {
  std::string data_dir = std::string(UNSEEN_SOURCE_DIR) + "/../shared/data/sequences";
  std::string extra;  // comma-separated folders of more sequences (each a sequence or a
                      // folder of sequences)
  int every = 10;
  std::string json;
  KnownModelPoseOptions pose;
};

struct SequenceFigures {
  std::string name;
  int starts = 0, found = 0, correct = 0, wrong_found = 0;
  double sum_ms = 0.0, sum_views_ms = 0.0;
  double sum_t_mm = 0.0, sum_r_deg = 0.0;  // over correct starts
};

// The candidate closest in rotation to the truth: its rank and its errors (for -v).
std::string NearestCandidate(const std::vector<Rigid3d>& candidates, const Rigid3d& truth) {
  int best = -1;
  PoseDifference nearest{0.0, 1e9};
  for (int i = 0; i < static_cast<int>(candidates.size()); ++i) {
    const PoseDifference d = Difference(truth, candidates[i]);
    if (d.rotation_rad < nearest.rotation_rad) {
      nearest = d;
      best = i;
    }
  }
  return fmt::format("nearest candidate {}: {:.0f} mm {:.0f} deg", best, 1e3 * nearest.translation,
                     nearest.rotation_rad * 180.0 / M_PI);
}

// Where the first view within 15 degrees of the truth ranks among all views, and its
// scores against the best view's (for -v: whether the view scoring or the alignment failed).
std::string TrueViewRank(const ViewBank& views, const Frame& frame, const RigCamera& rig_camera,
                         int camera, const PixelRect& box, const Rigid3d& truth) {
  const std::vector<ViewMatch> all = views.Match(frame.images[camera], box, views.size(), 0.0);
  for (int rank = 0; rank < static_cast<int>(all.size()); ++rank) {
    const Rigid3d pose =
        rig_camera.world_from_cam * views.CamFromObj(all[rank], rig_camera.intrinsics, box);
    if (Difference(truth, pose).rotation_rad * 180.0 / M_PI < 15.0) {
      return fmt::format(
          "true view rank {} (score {:.2f} = app {:.2f} sil {:.2f}; best {:.2f} = "
          "app {:.2f} sil {:.2f})",
          rank, all[rank].score, all[rank].appearance, all[rank].silhouette, all[0].score,
          all[0].appearance, all[0].silhouette);
    }
  }
  return "no view within 15 deg";
}

SequenceFigures Run(const fs::path& path, const Args& args, bool verbose) {
  const int every = args.every;
  SequenceFigures fig;
  fig.name = path.filename().string();
  Sequence sequence = Sequence::Open(path.string());
  if (!sequence.has_ground_truth() || sequence.model_path().empty()) {
    UNSEEN_LOG_WARN("{}: no ground truth or no model, skipped", fig.name);
    return fig;
  }
  TrackerOptions options;
  if (sequence.fps() > 0) options.frame_interval_s = 1.0 / sequence.fps();
  Tracker tracker(sequence.rig(), sequence.LoadModel(), options);
  Timer build_timer;
  KnownModelPoser poser(&tracker, args.pose);
  UNSEEN_LOG_INFO("{}: {} views in {:.0f} ms; oriented by {}", fig.name, poser.views().size(),
                  build_timer.ElapsedMilliseconds(),
                  tracker.given_model().HasAppearance() && options.photometric.enabled
                      ? "appearance"
                      : "silhouette only");
  const int camera = sequence.reference_camera();
  const RigCamera& rig_camera = sequence.rig().cameras[camera];
  for (int i = 0; i < sequence.num_frames(); i += every) {
    const std::optional<Rigid3d> truth = sequence.GroundTruth(i);
    if (!truth) continue;
    const Frame frame = sequence.ReadFrame(i);
    const PixelRect box = SilhouetteBox(tracker.given_model(), rig_camera.intrinsics,
                                        rig_camera.cam_from_world() * *truth);
    if (box.width() < 8 || box.height() < 8) continue;  // (nearly) out of view
    ++fig.starts;
    const KnownModelPoseResult r = poser.Find(frame, camera, box);
    const PoseDifference d = Difference(*truth, r.world_from_obj);
    const bool within = d.translation < 0.05 && d.rotation_rad * 180.0 / M_PI < 5.0;
    fig.found += r.found;
    fig.correct += r.found && within;
    fig.wrong_found += r.found && !within;
    fig.sum_ms += r.match_ms + r.align_ms;
    fig.sum_views_ms += r.match_ms;
    if (r.found && within) {
      fig.sum_t_mm += 1e3 * d.translation;
      fig.sum_r_deg += d.rotation_rad * 180.0 / M_PI;
    }
    if (verbose) {
      UNSEEN_LOG_INFO("{} frame {}: {}; error {:.1f} mm {:.1f} deg; {}; {}", fig.name, i,
                      r.BriefReport(), 1e3 * d.translation, d.rotation_rad * 180.0 / M_PI,
                      NearestCandidate(poser.Candidates(frame, camera, box), *truth),
                      TrueViewRank(poser.views(), frame, rig_camera, camera, box, *truth));
    }
  }
  return fig;
}

}  // namespace

int main(int argc, char** argv) {
  unseen::KeepFreedMemoryForReuse();
  Args args;
  CLI::App app{"unseen initial-pose benchmark: the known model's pose found from its box"};
  app.add_option("--data", args.data_dir, "Development sequences folder");
  app.add_option("--extra", args.extra, "Comma-separated folders of more sequences");
  app.add_option("--every", args.every, "Start at every n-th frame")->check(CLI::PositiveNumber);
  app.add_option("--json", args.json, "Write the figures here");
  app.add_option("--directions", args.pose.views.num_directions, "Viewing directions");
  app.add_option("--rolls", args.pose.views.num_rolls, "In-plane angles per direction");
  app.add_option("--patch", args.pose.views.patch_px, "Patch side, pixels");
  app.add_option("--silhouette-weight", args.pose.views.silhouette_weight,
                 "Weight of the silhouette cue");
  app.add_option("--appearance-step", args.pose.views.appearance_step,
                 "Grey difference counted as a full step, times the box's mean difference");
  app.add_option("--gradient-saturation", args.pose.views.gradient_saturation,
                 "Gradient magnitude where the silhouette cue saturates, times the mean");
  app.add_option("--candidates", args.pose.max_candidates, "Start poses tracked per start");
  app.add_option("--separation", args.pose.min_separation_deg,
                 "Least angle between two start poses, degrees");
  bool verbose = false;
  app.add_flag("-v,--verbose", verbose, "Log every start");
  CLI11_PARSE(app, argc, argv);
  try {
    const std::vector<fs::path> paths = bench::BenchmarkSequences(args.data_dir, args.extra);
    nlohmann::json results = nlohmann::json::array();
    fmt::print("{:<28} {:>6} {:>7} {:>7} {:>6} {:>8} {:>8} {:>9}\n", "sequence", "starts",
               "correct", "no pose", "wrong", "mm", "deg", "ms/start");
    int all_starts = 0, all_correct = 0;
    for (const fs::path& p : paths) {
      const SequenceFigures f = Run(p, args, verbose);
      if (f.starts == 0) continue;
      all_starts += f.starts;
      all_correct += f.correct;
      const double ok = std::max(f.correct, 1);
      fmt::print("{:<28} {:>6} {:>6.1f}% {:>6.1f}% {:>6} {:>8.1f} {:>8.2f} {:>9.0f}\n", f.name,
                 f.starts, 100.0 * f.correct / f.starts, 100.0 * (f.starts - f.found) / f.starts,
                 f.wrong_found, f.sum_t_mm / ok, f.sum_r_deg / ok, f.sum_ms / f.starts);
      results.push_back({{"sequence", f.name},
                         {"starts", f.starts},
                         {"correct", f.correct},
                         {"found", f.found},
                         {"wrong_found", f.wrong_found},
                         {"mean_translation_mm", f.sum_t_mm / ok},
                         {"mean_rotation_deg", f.sum_r_deg / ok},
                         {"ms_per_start", f.sum_ms / f.starts},
                         {"view_matching_ms_per_start", f.sum_views_ms / f.starts}});
    }
    if (all_starts > 0) {
      fmt::print("{:<28} {:>6} {:>6.1f}%\n", "all", all_starts, 100.0 * all_correct / all_starts);
    }
    if (!args.json.empty()) {
      std::ofstream(args.json)
          << nlohmann::json{{"every", args.every}, {"sequences", results}}.dump(2) << "\n";
    }
  } catch (const Error& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
  return 0;
}
