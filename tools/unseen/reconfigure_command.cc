// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// unseen reconfigure [--config reconfiguration.yaml] [--plot out.png] [--json out.json]: the
// thesis's dynamic camera reconfiguration (SPEC 7.2) with unseen's tracker in the loop;
// prints the visibility (5.1) with tracked poses, with true poses and with fixed cameras
// beside the thesis's statements, and the speed.
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "tools/unseen/commands.h"
#include "unseen/apps/camera_reconfiguration.h"
#include "unseen/apps/reconfiguration_plot.h"
#include "unseen/util/error.h"

namespace unseen::cli {

namespace {

struct ReconfigureArgs {
  std::string config = std::string(UNSEEN_SOURCE_DIR) + "/configs/apps/reconfiguration.yaml";
  std::string plot;
  std::string json;
  int frames = 0;
  int tracking_cameras = 0;
  bool no_tracker = false;
};

nlohmann::json ToJson(const ReconfigurationConfig& config, const ReconfigurationResult& r) {
  nlohmann::json j;
  j["frames"] = r.frames.size();
  j["fps_simulated"] = r.Fps();
  j["fps_without_image_synthesis"] = r.FpsWithoutSynthesis();
  j["seconds"] = {{"total", r.total_s},
                  {"synthesis", r.synth_s},
                  {"tracking", r.track_s},
                  {"planning", r.plan_s}};
  j["assigned_cameras"] = config.planner.assigned_cameras;
  j["lost_frames"] = r.lost_frames;
  j["position_error_m"] = {{"mean", r.mean_position_error_m}, {"max", r.max_position_error_m}};
  j["mean_lookahead"] = r.mean_lookahead;
  j["frames_tracked_not_above_truth"] = r.frames_tracked_not_above;
  j["max_tracked_excess"] = r.max_tracked_excess;
  for (int v = 0; v < kNumVariants; ++v) {
    nlohmann::json& s = j["variants"][VariantName(v)];
    s["mean_visibility"] = r.mean_visibility[v];
    s["camera_mean_visibility"] = r.camera_mean_visibility[v];
    s["frames_seen_by_fewer_than_m"] = r.frames_seen_by_fewer[v];
  }
  nlohmann::json& frames = j["per_frame"];
  for (const ReconfigurationFrame& f : r.frames) {
    nlohmann::json fj;
    const Eigen::Vector3d& t = f.true_world_from_obj.translation();
    const Eigen::Vector3d& e = f.tracked_world_from_obj.translation();
    fj["true_xz_m"] = {t.x(), t.z()};
    fj["tracked_xz_m"] = {e.x(), e.z()};
    fj["status"] = ToString(f.status);
    for (int v = 0; v < kNumVariants; ++v) {
      nlohmann::json cams = nlohmann::json::array();
      for (size_t i = 0; i < f.states[v].size(); ++i) {
        const VisibilityTerms& vt = f.visibility[v][i];
        cams.push_back({{"rail_m", f.states[v][i].rail_m},
                        {"pan_rad", f.states[v][i].pan_rad},
                        {"assigned", bool(f.assigned[v][i])},
                        {"V", vt.value},
                        {"area", vt.area},
                        {"distance", vt.distance},
                        {"angle", vt.angle}});
      }
      fj[VariantName(v)] = cams;
    }
    frames.push_back(fj);
  }
  return j;
}

void PrintReport(const ReconfigurationConfig& config, const ReconfigurationResult& r) {
  const int n = static_cast<int>(config.cameras.size());
  const int frames = static_cast<int>(r.frames.size());
  std::printf(
      "camera reconfiguration: %d frames at %.0f fps, %d reconfigurable cameras (M = %d), %zu "
      "columns, %d tracking cameras%s\n",
      frames, config.fps, n, config.planner.assigned_cameras, config.columns.size(),
      config.tracking_cameras, config.track ? "" : " (no tracker: planned on true poses)");
  std::printf(
      "tracking: %d frame(s) not tracked, position error mean %.1f mm, max %.1f mm    "
      "thesis: within 16 mm (real band-aid box)\n",
      r.lost_frames, 1e3 * r.mean_position_error_m, 1e3 * r.max_position_error_m);
  std::printf("visibility V (5.1), mean over frames:");
  for (const StageCamera& c : config.cameras) std::printf(" %8s", c.name.c_str());
  std::printf("      all  seen by < M\n");
  const char* const labels[] = {"reconfigured, tracked poses", "reconfigured, true poses   ",
                                "fixed cameras (default)    "};
  for (int v = 0; v < kNumVariants; ++v) {
    std::printf("  %s         ", labels[v]);
    for (int i = 0; i < n; ++i) std::printf(" %8.3f", r.camera_mean_visibility[v][i]);
    std::printf(" %8.3f  %4d frames\n", r.mean_visibility[v], r.frames_seen_by_fewer[v]);
  }
  std::printf(
      "tracked vs true poses: %.3f - %.3f = %+.3f; %d of %d frames equal or below (within 0.02), "
      "largest excess %.3f\n"
      "  thesis: \"values for the tracked case are equal to, or slightly below those for the "
      "ideal case\" (Fig. 5.17)\n",
      r.mean_visibility[kTrackedPoses], r.mean_visibility[kTruePoses],
      r.mean_visibility[kTrackedPoses] - r.mean_visibility[kTruePoses], r.frames_tracked_not_above,
      frames, r.max_tracked_excess);
  std::printf(
      "reconfiguration gain over fixed cameras: %+.3f V (%+.0f %%); seen by < M: %d -> %d "
      "frames\n"
      "  thesis: \"in all images, the OI is fully visible and at, or close to, the centre of the "
      "image frame\" (Fig. 5.16, Frame 153); no fixed-camera figure given\n",
      r.mean_visibility[kTruePoses] - r.mean_visibility[kFixedCameras],
      100.0 *
          (r.mean_visibility[kTruePoses] / std::max(1e-9, r.mean_visibility[kFixedCameras]) - 1),
      r.frames_seen_by_fewer[kFixedCameras], r.frames_seen_by_fewer[kTruePoses]);
  std::printf("planner: %d plans, %.1f demand instants looked ahead on average (%.2f ms a plan)\n",
              r.plans, r.mean_lookahead, r.plans > 0 ? 1e3 * r.plan_s / r.plans : 0.0);
  const double ms = 1e3 / std::max(1, frames);
  std::printf(
      "speed (one core): %.1f simulated fps (%.1f ms/frame: image synthesis %.1f, tracking %.1f, "
      "planning %.1f); %.1f fps without synthesising the tracking images    goal: 30 fps "
      "(real time); thesis: tracking at 30 Hz\n",
      r.Fps(), r.total_s * ms, r.synth_s * ms, r.track_s * ms, r.plan_s * ms,
      r.FpsWithoutSynthesis());
}

void RunReconfigure(const ReconfigureArgs& args) {
  ReconfigurationConfig config = LoadReconfigurationConfig(args.config);
  if (args.frames > 0) config.frames = args.frames;
  if (args.tracking_cameras > 0) config.tracking_cameras = args.tracking_cameras;
  if (args.no_tracker) config.track = false;
  const ReconfigurationResult result = RunReconfiguration(config);
  PrintReport(config, result);
  if (!args.json.empty()) {
    std::ofstream out(args.json);
    out << ToJson(config, result).dump(1) << "\n";
    UNSEEN_CHECK(out.good(), "{}: cannot write the reconfiguration JSON", args.json);
  }
  if (!args.plot.empty()) {
    UNSEEN_CHECK(cv::imwrite(args.plot, DrawReconfigurationPlot(config, result)),
                 "{}: cannot write the reconfiguration plot", args.plot);
  }
}

}  // namespace

void AddReconfigureCommand(CLI::App& app) {
  auto args = std::make_shared<ReconfigureArgs>();
  CLI::App* cmd = app.add_subcommand(
      "reconfigure",
      "Simulate the thesis's dynamic camera reconfiguration with the tracker in the loop");
  cmd->add_option("--config", args->config, "Configuration (configs/apps/reconfiguration.yaml)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--plot", args->plot, "Write a PNG of the top view and the visibility");
  cmd->add_option("--json", args->json, "Write the summary and per-frame records as JSON");
  cmd->add_option("--frames", args->frames, "Simulate only the first N frames")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--tracking-cameras", args->tracking_cameras,
                  "Tracking cameras in the rig (the thesis: 5)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--no-tracker", args->no_tracker,
                "Plan on the true poses in both runs (no images, no tracker)");
  cmd->callback([args] { RunReconfigure(*args); });
}

UNSEEN_REGISTER_COMMAND("reconfigure", AddReconfigureCommand);

}  // namespace unseen::cli
