// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// On-line modelling benchmark (SPEC 5) on the development sequences that have what it
// needs: the 5-camera rig (plane sweep over all cameras, stereo on the middle pair) and
// the real RGB-D cube (the sensor's depth); with --extra, any other sequences with depth
// images or several cameras (e.g. `unseen synth scenes/box_textured.yaml DIR --depth`), each
// with the depth source `unseen track --unknown` would take (NaturalDepthSource).
//  * depth: each source's depth map of the first frame against the object's true depth
//    (its model rendered at the ground truth): share of the object's pixels measured,
//    median and 90th-percentile error, ms per map;
//  * modeller: triangles and ms per build (the median of 5 builds of frame 0; builds per
//    second);
//  * tracking without the model, built from the first frame in the true object frame
//    (`unseen track --unknown --init gt --update-in-frame`), kept current by periodic
//    replacement and by incremental fusion (`--update periodic|incremental`), next to the
//    exact model: success at 5 cm / 5 deg, mean errors, and the drift of the object frame
//    (mean error over the last tenth of the frames);
//  * completeness of the final model: mean silhouette IoU with the true model over 14
//    views all round (6 faces, 8 corners of a cube about the object);
//  * the two-camera sources on a rectified real pair with true disparity (Middlebury's
//    aloe, from the opencv-doc package, at half size): coverage and bad-pixel rates.
// Prints a table and writes every row to a JSON file.
//
//   model_benchmark [--data DIR] [--extra SEQ...] [--json FILE]
// (e.g. --extra with the held-out two-camera renders of bench/heldout/, tracked with stereo
// depth as `unseen track SEQ --unknown` does by default.)
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>
#include <vector>

#include "unseen/eval/evaluation.h"
#include "unseen/eval/sequence_poses.h"
#include "unseen/image/image_io.h"
#include "unseen/io/sequence.h"
#include "unseen/model/model_updater.h"
#include "unseen/model/modeller.h"
#include "unseen/render/rasterizer.h"
#include "unseen/track/tracker.h"
#include "unseen/util/logging.h"
#include "unseen/util/timer.h"
#include "unseen/util/memory.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

struct Case {
  std::string sequence;  // folder
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

// A rectified stereo pair with its true disparity (px of the left image; 0 = unknown),
// scored by the stereo community's bad-pixel rate. Taken at half size: the sources search
// up to 128 px of disparity.
struct StereoPair {
  std::string name, left, right, disparity;
};

struct StereoRow {
  double coverage = 0.0;          // of the pixels with a true disparity, those measured
  double bad1 = 0.0, bad2 = 0.0;  // of the measured, off by more than 1 / 2 px
  double median_px = 0.0, ms = 0.0;
};

StereoRow ScoreStereoPair(const StereoPair& pair, DepthSourceKind kind) {
  StereoRow row;
  cv::Mat left, right, truth;
  cv::resize(LoadColorImage(pair.left), left, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  cv::resize(LoadColorImage(pair.right), right, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  cv::resize(cv::imread(pair.disparity, cv::IMREAD_UNCHANGED), truth, left.size(), 0, 0,
             cv::INTER_NEAREST);
  truth.convertTo(truth, CV_32F, 0.5);
  // A rig that makes disparity d a depth of focal * baseline / d.
  const double focal = 1000.0, baseline = 0.1, fb = focal * baseline;
  const PinholeCamera camera = PinholeCamera::Centered(left.cols, left.rows, focal);
  Rig rig;
  rig.cameras.push_back({"left", camera, Rigid3d()});
  rig.cameras.push_back(
      {"right", camera, Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(baseline, 0, 0))});
  double max_disparity = 0.0;
  cv::minMaxLoc(truth, nullptr, &max_disparity);
  DepthExtractionOptions options;
  options.source = kind;
  Frame frame;
  frame.images = {left, right};
  const std::unique_ptr<DepthSource> source = MakeDepthSource(rig, 0, options);
  Timer timer;
  const DepthMap map =
      source->Extract(frame, camera.ImageRect(), fb / (max_disparity + 4.0), fb / 4.0);
  row.ms = timer.ElapsedMilliseconds();
  std::vector<double> errors;
  int known = 0;
  for (int y = 0; y < truth.rows; ++y) {
    for (int x = 0; x < truth.cols; ++x) {
      const float d = truth.at<float>(y, x);
      if (!(d > 0.0f)) continue;
      ++known;
      const float z = map.depth.at<float>(y, x);
      if (z > 0.0f) errors.push_back(std::abs(fb / z - d));
    }
  }
  if (errors.empty()) return row;
  row.coverage = double(errors.size()) / known;
  row.bad1 = double(std::count_if(errors.begin(), errors.end(), [](double e) { return e > 1.0; })) /
             errors.size();
  row.bad2 = double(std::count_if(errors.begin(), errors.end(), [](double e) { return e > 2.0; })) /
             errors.size();
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  row.median_px = errors[errors.size() / 2];
  return row;
}

struct TrackRow {
  EvaluationResult eval;
  int rebuilds = 0;
  double end_mm = 0.0, end_deg = 0.0;  // mean errors over the last tenth of the frames
  double completeness = 0.0;           // of the final model (Completeness)
  double fuse_ms = 0.0;                // incremental: the last fusion
};

// Mean silhouette IoU of `model` with the true model seen from 14 directions about the
// object's centre (6 along the axes, 8 along the diagonals), 4 bounding radii away.
double Completeness(const Mesh& model, const Mesh& truth) {
  Eigen::Vector3f centre;
  float radius = 0.0f;
  truth.BoundingSphere(&centre, &radius);
  const PinholeCamera camera = PinholeCamera::Centered(160, 160, 160.0);
  std::vector<Eigen::Vector3d> directions;
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {-1.0, 1.0}) directions.push_back(sign * Eigen::Vector3d::Unit(axis));
  }
  for (int corner = 0; corner < 8; ++corner) {
    directions.emplace_back(corner & 1 ? 1 : -1, corner & 2 ? 1 : -1, corner & 4 ? 1 : -1);
  }
  RenderOptions options;
  options.write_color = false;
  double sum = 0.0;
  for (Eigen::Vector3d d : directions) {
    d.normalize();
    // The camera looks along -d at the centre from 4 radii away.
    const Eigen::Vector3d z = -d;
    const Eigen::Vector3d helper =
        std::abs(z.y()) < 0.9 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX();
    const Eigen::Vector3d x = helper.cross(z).normalized();
    Eigen::Matrix3d obj_from_cam;
    obj_from_cam << x, z.cross(x), z;
    const Rigid3d cam_from_obj =
        Rigid3d(Eigen::Quaterniond(obj_from_cam), centre.cast<double>() + 4.0 * radius * d)
            .Inverse();
    RenderBuffers a, b;
    Render(truth, camera, cam_from_obj, camera.ImageRect(), options, &a);
    Render(model, camera, cam_from_obj, camera.ImageRect(), options, &b);
    const int all = cv::countNonZero(a.mask | b.mask);
    sum += all > 0 ? double(cv::countNonZero(a.mask & b.mask)) / all : 0.0;
  }
  return sum / directions.size();
}

// Tracks the sequence from its first true pose with `model`, or (no model) with the
// modeller's model of frame 0 updated every 30 frames by `mode`.
TrackRow Track(const Sequence& sequence, const Modeller* modeller, std::optional<Mesh> model,
               ModelUpdateMode mode) {
  TrackRow row;
  const Rigid3d start = *sequence.GroundTruth(0);
  std::unique_ptr<ModelUpdater> updater;
  if (!model) {
    const Frame first = sequence.ReadFrame(0);
    const ModelBuild build = modeller->Build(first, start, PixelRect());
    if (!build.ok()) return row;
    ModelUpdateOptions update;
    update.mode = mode;
    update.asynchronous = false;
    updater = std::make_unique<ModelUpdater>(modeller, update);
    model = updater->Start(build);
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
  if (updater) {
    row.rebuilds = updater->stats().swapped;
    row.fuse_ms = updater->stats().fusion.fuse_ms;
  }
  row.eval = Evaluate(SequenceGroundTruth(sequence), records);
  const size_t tenth = std::max<size_t>(1, row.eval.per_frame.size() / 10);
  int scored = 0;
  for (size_t i = row.eval.per_frame.size() - tenth; i < row.eval.per_frame.size(); ++i) {
    const FrameError& e = row.eval.per_frame[i];
    if (!e.scored) continue;
    ++scored;
    row.end_mm += e.trans_err_norm_mm;
    row.end_deg += e.rot_err_angle_deg;
  }
  row.end_mm = scored ? row.end_mm / scored : NAN;
  row.end_deg = scored ? row.end_deg / scored : NAN;
  row.completeness = Completeness(tracker.given_model(), sequence.LoadModel());
  return row;
}

int Main(int argc, char** argv) {
  std::string data_dir = std::string(UNSEEN_SOURCE_DIR) + "/../shared/data/sequences";
  std::string json_path = "model_benchmark.json";
  CLI::App app("unseen on-line modelling benchmark");
  app.add_option("--data", data_dir, "Folder of the development sequences");
  std::vector<std::string> extra;
  app.add_option("--extra", extra, "More sequences (folders) with ground truth and a model");
  app.add_option("--json", json_path, "JSON file to write");
  CLI11_PARSE(app, argc, argv);
  SetVerbosity(0);  // warnings and errors only

  std::vector<Case> cases = {
      {data_dir + "/rig5_cube_fig312", DepthSourceKind::kPlaneSweep, ""},
      {data_dir + "/rig5_cube_fig312", DepthSourceKind::kStereo, "cam3"},
      {data_dir + "/visp_rbt_cube", DepthSourceKind::kSensor, ""},
  };
  for (const std::string& dir : extra) {
    // The source `unseen track --unknown` takes by default: its depth images, else stereo
    // for a side-by-side pair, else the plane sweep over its cameras.
    DepthSourceKind source = DepthSourceKind::kPlaneSweep;
    if (fs::is_directory(dir)) {
      const Sequence s = Sequence::Open(dir);
      source = NaturalDepthSource(s.rig(), s.reference_camera(), s.has_depth());
    }
    cases.push_back({dir, source, ""});
  }
  nlohmann::json rows = nlohmann::json::array();
  std::printf("%-18s %-10s | %8s %9s %8s | %9s %8s | %-11s %8s %8s %8s %8s %8s %8s\n", "sequence",
              "depth", "coverage", "median mm", "depth ms", "triangles", "mesh ms", "model",
              "success", "mean mm", "mean deg", "end mm", "end deg", "complete");
  for (const Case& c : cases) {
    const std::string name = fs::path(c.sequence).filename().string();
    if (!fs::is_directory(c.sequence)) {
      std::printf("%-18s skipped: %s not found\n", name.c_str(), c.sequence.c_str());
      continue;
    }
    const Sequence sequence = Sequence::Open(c.sequence);
    ModellerOptions options;
    options.depth.source = c.source;
    options.depth.stereo.other_camera = c.other_camera;
    const Modeller modeller(sequence.rig(), sequence.reference_camera(), options);
    // The time of a build: the median of kBuilds builds of frame 0 (the first one pays for
    // the process's first allocations and page faults, which a running modeller does not).
    constexpr int kBuilds = 5;
    const Frame frame0 = sequence.ReadFrame(0);
    std::vector<double> depth_ms, mesh_ms;
    ModelBuild build;
    for (int i = 0; i < kBuilds; ++i) {
      build = modeller.Build(frame0, *sequence.GroundTruth(0), PixelRect());
      depth_ms.push_back(build.depth_ms);
      mesh_ms.push_back(build.mesh_ms);
    }
    std::nth_element(depth_ms.begin(), depth_ms.begin() + kBuilds / 2, depth_ms.end());
    std::nth_element(mesh_ms.begin(), mesh_ms.begin() + kBuilds / 2, mesh_ms.end());
    build.depth_ms = depth_ms[kBuilds / 2];
    build.mesh_ms = mesh_ms[kBuilds / 2];
    const DepthRow depth = MeasureDepth(sequence, modeller, build);
    const int triangles = build.ok() ? build.mesh->num_triangles() : 0;
    nlohmann::json row = {{"sequence", name},
                          {"depth_source", ToString(c.source)},
                          {"depth_coverage", depth.coverage},
                          {"depth_median_error_mm", depth.median_mm},
                          {"depth_p90_error_mm", depth.p90_mm},
                          {"depth_ms", depth.ms},
                          {"model_triangles", triangles},
                          {"mesh_ms", build.mesh_ms},
                          {"builds_per_s", 1e3 / std::max(1e-3, depth.ms + build.mesh_ms)}};
    const std::pair<std::string, std::optional<ModelUpdateMode>> models[] = {
        {"periodic", ModelUpdateMode::kPeriodic},
        {"incremental", ModelUpdateMode::kIncremental},
        {"exact", std::nullopt}};
    for (const auto& [label, mode] : models) {
      const TrackRow t =
          mode ? Track(sequence, &modeller, std::nullopt, *mode)
               : Track(sequence, nullptr, sequence.LoadModel(), ModelUpdateMode::kNone);
      std::printf(
          "%-18s %-10s | %7.1f%% %9.1f %8.1f | %9d %8.1f | %-11s %7.1f%% %8.2f %8.2f "
          "%8.2f %8.2f %8.2f\n",
          name.c_str(), ToString(c.source).c_str(), 100 * depth.coverage, depth.median_mm, depth.ms,
          triangles, build.mesh_ms, label.c_str(), 100 * t.eval.success_rate,
          t.eval.trans_err_mm.mean, t.eval.rot_err_deg.mean, t.end_mm, t.end_deg, t.completeness);
      row[label] = {{"success_5cm5deg", t.eval.success_rate},
                    {"mean_trans_err_mm", t.eval.trans_err_mm.mean},
                    {"mean_rot_err_deg", t.eval.rot_err_deg.mean},
                    {"end_trans_err_mm", t.end_mm},
                    {"end_rot_err_deg", t.end_deg},
                    {"completeness_iou", t.completeness},
                    {"model_updates", t.rebuilds},
                    {"last_fusion_ms", t.fuse_ms}};
    }
    rows.push_back(row);
  }

  // Stereo pairs with true disparity, where their Debian packages put them.
  const std::vector<StereoPair> pairs = {{"aloe (opencv-doc)",
                                          "/usr/share/doc/opencv-doc/examples/data/aloeL.jpg",
                                          "/usr/share/doc/opencv-doc/examples/data/aloeR.jpg",
                                          "/usr/share/doc/opencv-doc/examples/data/aloeGT.png"}};
  nlohmann::json stereo_rows = nlohmann::json::array();
  std::printf("\n%-18s %-10s | %8s %8s %8s %9s %8s\n", "stereo pair", "depth", "coverage",
              "bad 1px", "bad 2px", "median px", "ms");
  for (const StereoPair& pair : pairs) {
    if (!fs::is_regular_file(pair.left) || !fs::is_regular_file(pair.disparity)) {
      std::printf("%-18s skipped: %s not found\n", pair.name.c_str(), pair.left.c_str());
      continue;
    }
    for (DepthSourceKind kind : {DepthSourceKind::kStereo, DepthSourceKind::kPlaneSweep}) {
      const StereoRow r = ScoreStereoPair(pair, kind);
      std::printf("%-18s %-10s | %7.1f%% %7.1f%% %7.1f%% %9.2f %8.1f\n", pair.name.c_str(),
                  ToString(kind).c_str(), 100 * r.coverage, 100 * r.bad1, 100 * r.bad2, r.median_px,
                  r.ms);
      stereo_rows.push_back({{"pair", pair.name},
                             {"depth_source", ToString(kind)},
                             {"half_size", true},
                             {"coverage", r.coverage},
                             {"bad_1px", r.bad1},
                             {"bad_2px", r.bad2},
                             {"median_error_px", r.median_px},
                             {"ms", r.ms}});
    }
  }
  rows = {{"sequences", rows}, {"stereo_pairs", stereo_rows}};
  std::ofstream out(json_path);
  out << rows.dump(1) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}

}  // namespace
}  // namespace unseen

int main(int argc, char** argv) {
  unseen::KeepFreedMemoryForReuse();
  return unseen::Main(argc, argv);
}
