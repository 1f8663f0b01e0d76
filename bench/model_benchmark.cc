// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// On-line modelling benchmark (SPEC 5) on the development sequences that have what it
// needs: the 5-camera rig (plane sweep over all cameras, stereo on the middle pair) and
// the real RGB-D cube (the sensor's depth).
//  * depth: each source's depth map of the first frame against the object's true depth
//    (its model rendered at the ground truth): share of the object's pixels measured,
//    median and 90th-percentile error, ms per map;
//  * modeller: triangles and ms per build;
//  * tracking without the model (built from the first frame in the true object frame,
//    rebuilt every 30 frames within the frame, as `unseen track --unknown --init gt
//    --update-in-frame`), next to the exact model: success at 5 cm / 5 deg, mean errors.
// Prints a table and writes every row to a JSON file.
//
//   model_benchmark [--data DIR] [--json FILE]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "unseen/eval/evaluation.h"
#include "unseen/eval/sequence_poses.h"
#include "unseen/io/sequence.h"
#include "unseen/model/model_updater.h"
#include "unseen/model/modeller.h"
#include "unseen/render/rasterizer.h"
#include "unseen/track/tracker.h"
#include "unseen/util/logging.h"
#include "unseen/util/timer.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

struct Case {
  std::string sequence;
  DepthSourceKind source;
  std::string other_camera;  // stereo's second camera
};

struct DepthRow {
  double coverage = 0.0, median_mm = 0.0, p90_mm = 0.0, ms = 0.0;
};

// The depth map of frame 0 against the true depth of the object (its model at the truth).
DepthRow MeasureDepth(const Sequence& sequence, const Modeller& modeller, const ModelBuild& build) {
  DepthRow row;
  row.ms = build.depth_ms;
  const RigCamera& cam = sequence.rig().cameras[modeller.reference()];
  RenderOptions options;
  options.write_color = false;
  RenderBuffers truth;
  Render(sequence.LoadModel(), cam.intrinsics,
         cam.cam_from_world() * *sequence.GroundTruth(0), cam.intrinsics.ImageRect(), options,
         &truth);
  std::vector<double> errors;
  int object = 0;
  for (int y = 0; y < truth.depth.rows; ++y) {
    for (int x = 0; x < truth.depth.cols; ++x) {
      const float z = truth.depth.at<float>(y, x);
      if (!(z > 0.0f)) continue;
      ++object;
      const float d = build.depth.depth.at<float>(y, x);
      if (d > 0.0f) errors.push_back(1e3 * std::abs(d - z));
    }
  }
  if (object == 0 || errors.empty()) return row;
  std::sort(errors.begin(), errors.end());
  row.coverage = double(errors.size()) / object;
  row.median_mm = errors[errors.size() / 2];
  row.p90_mm = errors[errors.size() * 9 / 10];
  return row;
}

struct TrackRow {
  EvaluationResult eval;
  int rebuilds = 0;
};

// Tracks the sequence from its first true pose with `model`, or (no model) with the
// modeller's model of frame 0 rebuilt every 30 frames.
TrackRow Track(const Sequence& sequence, const Modeller* modeller, std::optional<Mesh> model) {
  TrackRow row;
  const Rigid3d start = *sequence.GroundTruth(0);
  std::unique_ptr<ModelUpdater> updater;
  if (!model) {
    const Frame first = sequence.ReadFrame(0);
    ModelBuild build = modeller->Build(first, start, PixelRect());
    if (!build.ok()) return row;
    model = std::move(build.mesh);
    ModelUpdateOptions update;
    update.asynchronous = false;
    updater = std::make_unique<ModelUpdater>(modeller, update);
  }
  TrackerOptions options;
  if (sequence.fps() > 0) options.frame_interval_s = 1.0 / sequence.fps();
  Tracker tracker(sequence.rig(), std::move(*model), options);
  tracker.Initialize(start);
  std::vector<PoseRecord> records;
  for (int i = 0; i < sequence.num_frames(); ++i) {
    const Frame frame = sequence.ReadFrame(i);
    Timer timer;
    const TrackResult r = tracker.Track(frame);
    if (updater) updater->AfterTracked(frame, r, &tracker);
    records.push_back(r.ToPoseRecord(frame.frame_id, frame.time_s, timer.ElapsedMilliseconds()));
  }
  if (updater) row.rebuilds = updater->stats().swapped;
  row.eval = Evaluate(SequenceGroundTruth(sequence), records);
  return row;
}

int Main(int argc, char** argv) {
  std::string data_dir = std::string(UNSEEN_SOURCE_DIR) + "/../shared/data/sequences";
  std::string json_path = "model_benchmark.json";
  CLI::App app("unseen on-line modelling benchmark");
  app.add_option("--data", data_dir, "Folder of the development sequences");
  app.add_option("--json", json_path, "JSON file to write");
  CLI11_PARSE(app, argc, argv);
  SetVerbosity(0);  // warnings and errors only

  const std::vector<Case> cases = {
      {"rig5_cube_fig312", DepthSourceKind::kPlaneSweep, ""},
      {"rig5_cube_fig312", DepthSourceKind::kStereo, "cam3"},
      {"visp_rbt_cube", DepthSourceKind::kSensor, ""},
  };
  nlohmann::json rows = nlohmann::json::array();
  std::printf("%-18s %-10s | %8s %9s %8s %8s | %9s %8s | %8s %9s %8s | %8s %9s %8s\n",
              "sequence", "depth", "coverage", "median mm", "p90 mm", "depth ms", "triangles",
              "mesh ms", "on-line", "mean mm", "mean deg", "exact", "mean mm", "mean deg");
  for (const Case& c : cases) {
    const std::string dir = (fs::path(data_dir) / c.sequence).string();
    if (!fs::is_directory(dir)) {
      std::printf("%-18s skipped: not found in %s\n", c.sequence.c_str(), data_dir.c_str());
      continue;
    }
    const Sequence sequence = Sequence::Open(dir);
    ModellerOptions options;
    options.depth.source = c.source;
    options.depth.stereo.other_camera = c.other_camera;
    const Modeller modeller(sequence.rig(), sequence.reference_camera(), options);
    const ModelBuild build = modeller.Build(sequence.ReadFrame(0), *sequence.GroundTruth(0),
                                            PixelRect());
    const DepthRow depth = MeasureDepth(sequence, modeller, build);
    const TrackRow online = Track(sequence, &modeller, std::nullopt);
    const TrackRow exact = Track(sequence, nullptr, sequence.LoadModel());
    const int triangles = build.ok() ? build.mesh->num_triangles() : 0;
    std::printf("%-18s %-10s | %7.1f%% %9.1f %8.1f %8.1f | %9d %8.1f | %7.1f%% %9.2f %8.2f | "
                "%7.1f%% %9.2f %8.2f\n",
                c.sequence.c_str(), ToString(c.source).c_str(), 100 * depth.coverage,
                depth.median_mm, depth.p90_mm, depth.ms, triangles, build.mesh_ms,
                100 * online.eval.success_rate, online.eval.trans_err_mm.mean,
                online.eval.rot_err_deg.mean, 100 * exact.eval.success_rate,
                exact.eval.trans_err_mm.mean, exact.eval.rot_err_deg.mean);
    rows.push_back({{"sequence", c.sequence},
                    {"depth_source", ToString(c.source)},
                    {"depth_coverage", depth.coverage},
                    {"depth_median_error_mm", depth.median_mm},
                    {"depth_p90_error_mm", depth.p90_mm},
                    {"depth_ms", depth.ms},
                    {"model_triangles", triangles},
                    {"mesh_ms", build.mesh_ms},
                    {"online_success_5cm5deg", online.eval.success_rate},
                    {"online_mean_trans_err_mm", online.eval.trans_err_mm.mean},
                    {"online_mean_rot_err_deg", online.eval.rot_err_deg.mean},
                    {"online_rebuilds", online.rebuilds},
                    {"exact_success_5cm5deg", exact.eval.success_rate},
                    {"exact_mean_trans_err_mm", exact.eval.trans_err_mm.mean},
                    {"exact_mean_rot_err_deg", exact.eval.rot_err_deg.mean}});
  }
  std::ofstream out(json_path);
  out << rows.dump(1) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}

}  // namespace
}  // namespace unseen

int main(int argc, char** argv) { return unseen::Main(argc, argv); }
