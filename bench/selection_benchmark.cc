// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Object-of-interest selection (SPEC 4, system/system.h's selection before tracking): every
// frame of each sequence goes through the interest filter bank, the motion segmentation
// and the region selection, as `unseen run` does until it tracks; the selected region is
// scored against the object's true visible mask (camK/mask_visib, or the model rendered at
// the true pose when the sequence has none). Reports, per sequence: frames judged (the
// bank ready), frames with a selection, right selections (mask IoU >= 0.5), false ones,
// the first frame with a selection and with a right one, and the time per frame.
// Prints a table; writes JSON with --json.
//
//   build/bench/selection_benchmark [--data DIR] [--extra DIR,...] [--config system.yaml]
//                                   [--frames N] [--json out.json]
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "bench_sequences.h"
#include "unseen/io/sequence.h"
#include "unseen/render/rasterizer.h"
#include "unseen/select/motion_segmentation.h"
#include "unseen/select/region_selection.h"
#include "unseen/system/system_config.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/timer.h"
#include "unseen/util/memory.h"

namespace {

using namespace unseen;
namespace fs = std::filesystem;

struct Args {
  std::string data_dir = std::string(UNSEEN_SOURCE_DIR) + "/../shared/data/sequences";
  std::string extra;   // comma-separated folders of more sequences
  std::string config;  // system.yaml: filters, regions, segmentation, selection
  int max_frames = 0;  // 0: all
  std::string json;
};

struct SequenceFigures {
  std::string name;
  int frames = 0, judged = 0, selected = 0, right = 0, wrong = 0;
  int right_box = 0;  // box IoU >= 0.5 (what the pose is started from)
  int first_selection = -1, first_right = -1;
  double sum_iou = 0.0;  // over right selections
  double sum_ms = 0.0;
};

// The object's visible pixels in frame `frame_id` (CV_8UC1, non-zero on the object): the
// sequence's mask_visib image, else the model rendered at the true pose; empty when
// neither is known.
cv::Mat TrueMask(const Sequence& sequence, const fs::path& dir, const RigCamera& camera,
                 const std::optional<Mesh>& model, int frame_index, int frame_id) {
  const fs::path file =
      dir / camera.name / "mask_visib" / fmt::format("{:06d}_000000.png", frame_id);
  if (fs::exists(file)) return cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  const std::optional<Rigid3d> truth = sequence.GroundTruth(frame_index);
  if (!truth || !model) return cv::Mat();
  RenderBuffers buffers;
  Render(*model, camera.intrinsics, camera.cam_from_world() * *truth, camera.intrinsics.ImageRect(),
         RenderOptions{}, &buffers);
  cv::Mat mask = cv::Mat::zeros(camera.intrinsics.height, camera.intrinsics.width, CV_8UC1);
  const PixelRect& roi = buffers.roi;
  if (!roi.empty()) buffers.mask.copyTo(mask(cv::Rect(roi.x0, roi.y0, roi.width(), roi.height())));
  return mask;
}

double BoxIou(const cv::Rect& a, const cv::Rect& b) {
  const double inter = (a & b).area(), uni = a.area() + b.area() - inter;
  return uni > 0 ? inter / uni : 0.0;
}

double MaskIou(const cv::Mat& a, const cv::Mat& b) {
  const double inter = cv::countNonZero(a & b), uni = cv::countNonZero(a | b);
  return uni > 0 ? inter / uni : 0.0;
}

SequenceFigures Run(const fs::path& path, const Args& args) {
  SequenceFigures fig;
  fig.name = path.filename().string();
  const Sequence sequence = Sequence::Open(path.string());
  SystemConfig config = args.config.empty() ? SystemConfig() : LoadSystemConfig(args.config);
  InterestFilterBank bank;
  if (config.filters) {
    bank = std::move(*config.filters);
  } else {
    bank.Add(std::make_unique<MotionFilter>(MotionFilterOptions()));
  }
  const SystemOptions& options = config.system;
  MotionSegmenter segmenter(options.segmentation);
  const int reference = sequence.reference_camera();
  const RigCamera& camera = sequence.rig().cameras[reference];
  std::optional<Mesh> model;
  if (!sequence.model_path().empty()) model = sequence.LoadModel();
  const int n = args.max_frames > 0 ? std::min(args.max_frames, sequence.num_frames())
                                    : sequence.num_frames();
  for (int i = 0; i < n; ++i) {
    const Frame frame = sequence.ReadFrame(i);
    ++fig.frames;
    Timer timer;
    FilterFrame in;
    in.image = frame.images[reference];
    if (!frame.depths.empty()) in.depth = frame.depths[reference];
    in.camera = camera.intrinsics;
    in.world_from_cam = camera.world_from_cam;
    in.time_s = frame.time_s;
    const cv::Mat interest = bank.Apply(in);
    const cv::Mat segments = segmenter.Segment(in.image, interest);
    if (!bank.ready()) continue;
    const cv::Mat labels = options.regions == RegionSource::kMotion
                               ? segments
                               : InterestRegions(interest, options.selection.min_interest);
    const RegionSelection selection =
        SelectRegion(labels, interest, cv::Mat(), in.depth, camera.intrinsics, options.selection);
    fig.sum_ms += timer.ElapsedMilliseconds();
    const cv::Mat truth = TrueMask(sequence, path, camera, model, i, frame.frame_id);
    if (truth.empty()) continue;
    ++fig.judged;
    if (!selection.found()) continue;
    ++fig.selected;
    if (fig.first_selection < 0) fig.first_selection = i;
    const cv::Mat region = labels == selection.object().label;
    const double iou = MaskIou(region, truth > 0);
    fig.right_box += BoxIou(cv::boundingRect(region), cv::boundingRect(truth)) >= 0.5;
    if (iou >= 0.5) {
      ++fig.right;
      fig.sum_iou += iou;
      if (fig.first_right < 0) fig.first_right = i;
    } else {
      ++fig.wrong;
    }
  }
  return fig;
}

}  // namespace

int main(int argc, char** argv) {
  unseen::KeepFreedMemoryForReuse();
  Args args;
  CLI::App app{"unseen selection benchmark: the object of interest found by the selection"};
  app.add_option("--data", args.data_dir, "Sequences folder (or one sequence)");
  app.add_option("--extra", args.extra, "Comma-separated folders of more sequences");
  app.add_option("--config", args.config,
                 "System configuration (filters, regions, segmentation, selection)");
  app.add_option("--frames", args.max_frames, "At most this many frames per sequence");
  app.add_option("--json", args.json, "Write the figures here");
  CLI11_PARSE(app, argc, argv);
  try {
    const std::vector<fs::path> paths = bench::BenchmarkSequences(args.data_dir, args.extra);
    nlohmann::json results = nlohmann::json::array();
    fmt::print("{:<28} {:>6} {:>6} {:>8} {:>7} {:>6} {:>6} {:>6} {:>6} {:>6} {:>7}\n", "sequence",
               "frames", "judged", "selected", "right", "false", "IoU", "first", "1st ok", "ms",
               "box ok");
    for (const fs::path& p : paths) {
      const SequenceFigures f = Run(p, args);
      if (f.judged == 0) {
        UNSEEN_LOG_WARN("{}: no frame with a true mask judged, skipped", f.name);
        continue;
      }
      fmt::print(
          "{:<28} {:>6} {:>6} {:>8} {:>6.1f}% {:>6} {:>6.2f} {:>6} {:>6} {:>6.1f} {:>6.1f}%\n",
          f.name, f.frames, f.judged, f.selected, 100.0 * f.right / f.judged, f.wrong,
          f.right ? f.sum_iou / f.right : 0.0, f.first_selection, f.first_right,
          f.sum_ms / f.frames, 100.0 * f.right_box / f.judged);
      results.push_back({{"sequence", f.name},
                         {"frames", f.frames},
                         {"judged", f.judged},
                         {"selected", f.selected},
                         {"right", f.right},
                         {"right_share", static_cast<double>(f.right) / f.judged},
                         {"false", f.wrong},
                         {"right_box", f.right_box},
                         {"mean_iou_right", f.right ? f.sum_iou / f.right : 0.0},
                         {"first_selection_frame", f.first_selection},
                         {"first_right_frame", f.first_right},
                         {"ms_per_frame", f.sum_ms / f.frames}});
    }
    if (!args.json.empty()) {
      std::ofstream(args.json) << nlohmann::json{{"config",
                                                  args.config.empty() ? "default" : args.config},
                                                 {"sequences", results}}
                                      .dump(2)
                               << "\n";
    }
  } catch (const Error& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 1;
  }
  return 0;
}
