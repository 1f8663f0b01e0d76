// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// unseen synth SCENE.yaml OUT_DIR: renders a synthetic sequence (scenes/*.yaml) with ground
// truth, the model in millimetres, masks and optional depth.
#include <cstdio>
#include <memory>
#include <string>

#include "tools/unseen/commands.h"
#include "unseen/synth/scene.h"
#include "unseen/synth/synthesizer.h"
#include "unseen/util/logging.h"

namespace unseen::cli {

namespace {

struct SynthArgs {
  std::string scene;
  std::string out_dir;
  int frames = -1;
  int64_t seed = -1;
  bool depth = false;
  bool quiet = false;
};

}  // namespace

void AddSynthCommand(CLI::App& app) {
  auto args = std::make_shared<SynthArgs>();
  CLI::App* cmd = app.add_subcommand(
      "synth",
      "Render a synthetic sequence (DATASET.md layout, with ground truth) from a YAML scene");
  cmd->add_option("scene", args->scene, "Scene file (see scenes/README.md)")->required();
  cmd->add_option("out_dir", args->out_dir, "Output sequence folder (created)")->required();
  cmd->add_option("--frames", args->frames, "Render only the first N frames")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--seed", args->seed, "Override the scene's random seed")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--depth", args->depth, "Also write 16-bit depth images");
  cmd->add_flag("--quiet", args->quiet, "No progress line, warnings and errors only");
  cmd->callback([args] {
    if (args->quiet) SetVerbosity(0);
    const Scene scene = LoadScene(args->scene);
    SynthOptions options;
    options.max_frames = args->frames;
    if (args->seed >= 0) options.seed = static_cast<uint64_t>(args->seed);
    options.force_depth = args->depth;
    options.progress = !args->quiet;
    const SynthSummary s = Synthesize(scene, args->out_dir, options);
    if (!args->quiet) {
      std::printf("%s: %d frames x %d cameras in %.1f s (%.3f s per frame)\n",
                  args->out_dir.c_str(), s.frames, s.cameras, s.seconds, s.seconds_per_frame);
    }
  });
}

UNSEEN_REGISTER_COMMAND("synth", AddSynthCommand);

}  // namespace unseen::cli
