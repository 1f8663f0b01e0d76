// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Soak benchmark: the tracker over a long stream (10 000 frames by default) made from a
// synthetic sequence rendered once in memory (scenes/cube_clutter.yaml at 320x240, 300
// frames) and played again and again with faults injected (track/soak.h): black frames,
// frames of noise, frames without an image, jumps ahead, a jump back to the first frame at
// every replay, the model replaced by a coarser-textured or 1 % larger copy. The tracker
// loses and re-acquires the object many times. Prints the counts, the frame rate and the
// resident memory sampled through the run; writes them to a JSON file. Exits 1 when a pose
// was NaN, the tracker threw, or the resident memory grew by more than the bound between
// the first and the last quarter of the run.
//
//   soak_benchmark [--frames 10000] [--seed 1] [--json soak_benchmark.json]
//                  [--scene scenes/cube_clutter.yaml] [--sequence-frames 300]
//                  [--width 320 --height 240] [--max-rss-growth-mb 20] [--threads 1]
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>
#include <string>
#include <thread>

#include "unseen/synth/scene.h"
#include "unseen/synth/synthesizer.h"
#include "unseen/track/soak.h"
#include "unseen/track/tracker_options.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/memory.h"
#include "unseen/util/timer.h"

namespace unseen {
namespace {

struct BenchArgs {
  std::string scene = std::string(UNSEEN_SOURCE_DIR) + "/scenes/cube_clutter.yaml";
  int sequence_frames = 300;      // frames of the scene rendered and played in a loop
  int width = 320, height = 240;  // the scene's camera resized to this, same field of view
  std::string json_path = "soak_benchmark.json";
  double max_rss_growth_mb = 20.0;  // bound on the first-to-last-quarter growth, MB
  int threads = 1;                  // TrackerOptions::threads
  SoakOptions soak;
};

// The scene's first camera resized to width x height with the same horizontal field of view
// and the principal point in the middle; the other cameras dropped.
void Resize(int width, int height, Scene* scene) {
  UNSEEN_CHECK(width >= 64 && height >= 48, "soak_benchmark: --width {} --height {} below 64x48",
               width, height);
  RigCamera camera = scene->rig.cameras.at(0);
  const double focal = camera.intrinsics.fx * width / camera.intrinsics.width;
  camera.intrinsics = PinholeCamera::Centered(width, height, focal);
  scene->rig.cameras = {camera};
  scene->reference_camera = 0;
}

// Renders the scene into memory: 8-bit images (as a camera delivers them), the true poses,
// and the models the run swaps between.
SoakSource RenderSource(const BenchArgs& args) {
  Scene scene = LoadScene(args.scene);
  Resize(args.width, args.height, &scene);
  scene.frames = args.sequence_frames;
  scene.Check();
  const Synthesizer synth(scene);
  SoakSource source;
  source.rig = scene.rig;
  for (int f = 0; f < synth.num_frames(); ++f) {
    SynthFrame frame = synth.RenderFrame(f);
    std::vector<cv::Mat> images;
    for (const cv::Mat& image : frame.images) {
      cv::Mat bytes;
      image.convertTo(bytes, CV_8UC3, 255.0);
      images.push_back(bytes);
    }
    source.images.push_back(std::move(images));
    source.world_from_obj.push_back(frame.world_from_obj);
  }
  const Mesh& mesh = synth.object_mesh();
  ObjectSpec coarse_spec = scene.object;
  coarse_spec.texture_px = std::max(16, coarse_spec.texture_px / 2);
  Mesh larger = mesh;
  larger.Scale(1.01f);
  source.models = {mesh, BuildObjectMesh(coarse_spec), larger};
  return source;
}

nlohmann::json ToJson(const BenchArgs& args, const SoakResult& r, double render_s, double total_s,
                      int64_t rss_before_render, bool pass) {
  nlohmann::json memory = nlohmann::json::array();
  for (const SoakResult::MemorySample& s : r.memory) {
    memory.push_back({{"frame", s.frame}, {"rss_mb", s.resident_bytes / 1e6}});
  }
  const SoakOptions& o = args.soak;
  return {
      {"benchmark", "soak"},
      {"hardware_threads", static_cast<int>(std::thread::hardware_concurrency())},
      {"scene", args.scene.substr(args.scene.find_last_of('/') + 1)},
      {"image_size", {args.width, args.height}},
      {"sequence_frames", args.sequence_frames},
      {"threads", args.threads},
      {"options",
       {{"frames", o.frames},
        {"seed", o.seed},
        {"black_rate", o.black_rate},
        {"noise_rate", o.noise_rate},
        {"missing_rate", o.missing_rate},
        {"max_burst_frames", o.max_burst_frames},
        {"jump_rate", o.jump_rate},
        {"min_jump_frames", o.min_jump_frames},
        {"max_jump_frames", o.max_jump_frames},
        {"model_swap_rate", o.model_swap_rate},
        {"reinitialize_after_lost", o.reinitialize_after_lost},
        {"far_translation_m", o.far_translation_m},
        {"far_rotation_rad", o.far_rotation_rad}}},
      {"frames", r.frames},
      {"sequence_frames_played", r.sequence_frames},
      {"tracking_frames", r.tracking_frames},
      {"lost_frames", r.lost_frames},
      {"reacquisitions", r.reacquisitions},
      {"reinitializations", r.reinitializations},
      {"within_5cm_5deg", r.within_5cm_5deg},
      {"tracking_far", r.tracking_far},
      {"confident_far", r.confident_far},
      {"nan_poses", r.nan_poses},
      {"exceptions", r.exceptions},
      {"exception_messages", r.exception_messages},
      {"injected",
       {{"black_frames", r.black_frames},
        {"noise_frames", r.noise_frames},
        {"missing_frames", r.missing_frames},
        {"jumps", r.jumps},
        {"replays", r.replays},
        {"model_swaps", r.model_swaps}}},
      {"fps", r.Fps()},
      {"track_seconds", r.track_seconds},
      {"track_cpu_seconds", r.track_cpu_seconds},
      {"cpu_ms_per_frame", r.CpuMsPerFrame()},
      {"render_seconds", render_s},
      {"total_seconds", total_s},
      {"rss_mb",
       {{"before_render", rss_before_render / 1e6},
        {"start", r.StartResidentBytes() / 1e6},
        {"end", r.EndResidentBytes() / 1e6},
        {"max", r.MaxResidentBytes() / 1e6},
        {"growth_first_to_last_quarter", r.ResidentGrowthBytes() / 1e6},
        {"growth_bound", args.max_rss_growth_mb}}},
      {"memory_samples", memory},
      {"pass", pass},
  };
}

int Main(int argc, char** argv) {
  BenchArgs args;
  SoakOptions& o = args.soak;
  CLI::App app{
      "unseen soak benchmark: the tracker over a long stream with losses, "
      "re-acquisitions and injected faults; memory must stay flat"};
  app.add_option("--frames", o.frames, "Frames to track");
  app.add_option("--seed", o.seed, "Seed of the injected faults");
  app.add_option("--json", args.json_path, "Results JSON to write");
  app.add_option("--scene", args.scene, "Scene rendered as the played sequence (YAML)");
  app.add_option("--sequence-frames", args.sequence_frames, "Frames of the scene rendered");
  app.add_option("--width", args.width, "Image width, px");
  app.add_option("--height", args.height, "Image height, px");
  app.add_option("--max-rss-growth-mb", args.max_rss_growth_mb,
                 "Largest allowed growth of resident memory, first to last quarter, MB");
  app.add_option("--threads", args.threads, "Tracker threads (0 = all cores)");
  app.add_option("--black-rate", o.black_rate, "Probability per frame of black frames");
  app.add_option("--noise-rate", o.noise_rate, "Probability per frame of noise frames");
  app.add_option("--missing-rate", o.missing_rate, "Probability per frame of missing frames");
  app.add_option("--jump-rate", o.jump_rate, "Probability per frame of a jump ahead");
  app.add_option("--model-swap-rate", o.model_swap_rate, "Probability per frame of a model swap");
  app.add_option("--reinitialize-after-lost", o.reinitialize_after_lost,
                 "Re-initialise at the true pose after this many lost frames (0 = never)");
  bool verbose = false;
  app.add_flag("-v,--verbose", verbose, "Debug log (e.g. every frame tracked far from the truth)");
  CLI11_PARSE(app, argc, argv);
  SetVerbosity(verbose ? 2 : 1);
  o.Check();
  UNSEEN_CHECK(args.sequence_frames >= 2, "soak_benchmark: --sequence-frames {} must be >= 2",
               args.sequence_frames);
  UNSEEN_CHECK(args.max_rss_growth_mb > 0.0, "soak_benchmark: --max-rss-growth-mb {} must be > 0",
               args.max_rss_growth_mb);
  cv::setNumThreads(1);

  Timer total;
  const int64_t rss_before_render = ResidentMemoryBytes();
  std::printf("soak: rendering %d frames of %s at %dx%d ...\n", args.sequence_frames,
              args.scene.c_str(), args.width, args.height);
  std::fflush(stdout);
  const SoakSource source = RenderSource(args);
  const double render_s = total.ElapsedSeconds();
  std::printf("soak: rendered in %.1f s; tracking %d frames\n", render_s, o.frames);
  std::fflush(stdout);

  TrackerOptions tracker_options;
  tracker_options.threads = args.threads;
  tracker_options.frame_interval_s = 1.0 / 30.0;
  tracker_options.Check();
  const int report_every = std::max(1, o.frames / 10);
  const SoakResult r = RunSoak(source, tracker_options, o, [&](const SoakResult& p) {
    const int frame = p.memory.back().frame;
    if (frame == 0 || frame % report_every != 0) return;
    std::printf("  frame %6d: RSS %7.1f MB, %6.1f fps, %d lost, %d re-acquisitions\n", frame,
                p.memory.back().resident_bytes / 1e6, p.Fps(), p.lost_frames, p.reacquisitions);
    std::fflush(stdout);
  });
  const double total_s = total.ElapsedSeconds();

  const double growth_mb = r.ResidentGrowthBytes() / 1e6;
  const bool memory_flat = growth_mb <= args.max_rss_growth_mb;
  const bool pass = r.nan_poses == 0 && r.exceptions == 0 && memory_flat;
  std::printf("\n== soak (%s)\n", pass ? "pass" : "FAIL");
  std::printf("frames              %d (%d of the sequence, %d replays, %d jumps)\n", r.frames,
              r.sequence_frames, r.replays, r.jumps);
  std::printf("injected            %d black, %d noise, %d missing frames, %d model swaps\n",
              r.black_frames, r.noise_frames, r.missing_frames, r.model_swaps);
  std::printf("reported            %d tracking, %d lost\n", r.tracking_frames, r.lost_frames);
  std::printf(
      "re-acquisitions     %d (lost -> tracking by the tracker), %d re-initialisations "
      "after %d lost frames\n",
      r.reacquisitions, r.reinitializations, o.reinitialize_after_lost);
  std::printf(
      "accuracy            %d of %d sequence frames tracked within 5 cm/5 deg; %d reported "
      "tracking further than %.0f mm/%.0f deg, %d of them with a confidence of at least "
      "%.2f\n",
      r.within_5cm_5deg, r.sequence_frames, r.tracking_far, 1e3 * o.far_translation_m,
      o.far_rotation_rad * 180.0 / M_PI, r.confident_far, tracker_options.failure.lost_confidence);
  std::printf("NaN poses           %d (must be 0)\n", r.nan_poses);
  std::printf("exceptions          %d (must be 0)\n", r.exceptions);
  for (const std::string& m : r.exception_messages) std::printf("  %s\n", m.c_str());
  std::printf(
      "RSS                 start %.1f MB, end %.1f MB, max %.1f MB (%.1f MB before "
      "rendering)\n",
      r.StartResidentBytes() / 1e6, r.EndResidentBytes() / 1e6, r.MaxResidentBytes() / 1e6,
      rss_before_render / 1e6);
  std::printf("RSS growth          %+.2f MB first to last quarter (bound %.1f MB): %s\n", growth_mb,
              args.max_rss_growth_mb, memory_flat ? "flat" : "GROWING");
  std::printf(
      "speed               %.1f fps of tracking (%.1f s wall clock; %.2f ms of CPU a frame, "
      "%.1f fps on an idle core), %.1f s in all with %.1f s of rendering\n",
      r.Fps(), r.track_seconds, r.CpuMsPerFrame(),
      r.CpuMsPerFrame() > 0 ? 1e3 / r.CpuMsPerFrame() : 0.0, total_s, render_s);

  std::ofstream out(args.json_path);
  UNSEEN_CHECK(out.good(), "{}: cannot write the results", args.json_path);
  out << ToJson(args, r, render_s, total_s, rss_before_render, pass).dump(1) << "\n";
  std::printf("\nResults: %s\n", args.json_path.c_str());
  return pass ? 0 : 1;
}

}  // namespace
}  // namespace unseen

int main(int argc, char** argv) {
  unseen::KeepFreedMemoryForReuse();
  try {
    return unseen::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "soak_benchmark: error: %s\n", e.what());
    return 1;
  }
}
