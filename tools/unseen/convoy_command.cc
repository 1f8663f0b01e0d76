// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// unseen convoy [--config convoy.yaml] [--plot out.png] [--json out.json] [--frames N]: the
// thesis's convoy-following simulation (SPEC 7.1) with unseen's tracker closing the loop;
// prints the run's figures beside the thesis's.
#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "tools/unseen/commands.h"
#include "unseen/apps/convoy.h"
#include "unseen/apps/convoy_plot.h"
#include "unseen/image/image_io.h"
#include "unseen/util/error.h"

namespace unseen::cli {

namespace {

struct ConvoyArgs {
  std::string config;
  std::string plot;
  std::string json;
  std::string images;
  int frames = 0;
  bool no_tracker = false;
};

void RunConvoy(const ConvoyArgs& args) {
  ConvoyOptions options = args.config.empty() ? ConvoyOptions() : LoadConvoyOptions(args.config);
  if (args.no_tracker) options.use_tracker = false;
  // One core (the thesis's figure): OpenCV's own loops run on the calling thread too.
  if (options.tracker.threads == 1) cv::setNumThreads(1);
  ConvoySimulation simulation(options);
  std::printf(
      "convoy: %s, %d frames%s\n",
      args.config.empty() ? "built-in thesis run" : args.config.c_str(),
      args.frames > 0 ? std::min(args.frames, simulation.NumFrames()) : simulation.NumFrames(),
      options.use_tracker ? "" : " (no tracker: the rendered pose is measured)");
  std::function<void(const ConvoyFrame&)> save_image;
  if (!args.images.empty()) {
    std::filesystem::create_directories(args.images);
    save_image = [&](const ConvoyFrame& f) {
      if (simulation.last_image().empty()) return;
      SaveColorImage(fmt::format("{}/{:06d}.png", args.images, f.frame), simulation.last_image());
    };
  }
  const ConvoyResult result = simulation.Run(args.frames, save_image);
  std::fputs(result.summary.Report().c_str(), stdout);
  if (!args.json.empty()) {
    std::ofstream out(args.json);
    out << result.ToJson().dump(1) << "\n";
    UNSEEN_CHECK(out.good(), "{}: cannot write the convoy JSON", args.json);
  }
  if (!args.plot.empty()) SaveConvoyPlot(args.plot, result);
}

}  // namespace

void AddConvoyCommand(CLI::App& app) {
  auto args = std::make_shared<ConvoyArgs>();
  CLI::App* cmd = app.add_subcommand(
      "convoy", "Simulate the thesis's convoy following with the tracker in the loop");
  cmd->add_option("--config", args->config, "Convoy configuration (configs/apps/convoy.yaml)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--plot", args->plot, "Write a PNG of the paths and errors");
  cmd->add_option("--json", args->json, "Write the summary and per-frame records as JSON");
  cmd->add_option("--frames", args->frames, "Simulate only the first N frames")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--images", args->images, "Write the follower's camera images to this folder");
  cmd->add_flag("--no-tracker", args->no_tracker,
                "Measure the rendered pose instead of tracking (controller only, no images)");
  cmd->callback([args] { RunConvoy(*args); });
}

UNSEEN_REGISTER_COMMAND("convoy", AddConvoyCommand);

}  // namespace unseen::cli
