// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include <cstdio>

#include <Eigen/Core>
#include <opencv2/core/version.hpp>

#include "tools/unseen/commands.h"

namespace unseen::cli {

void AddVersionCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("version", "Print the version and the libraries used");
  cmd->callback([] {
    std::printf("unseen 0.1.0 (OpenCV %s, Eigen %d.%d.%d)\n", CV_VERSION, EIGEN_WORLD_VERSION,
                EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION);
  });
}

UNSEEN_REGISTER_COMMAND("version", AddVersionCommand);

}  // namespace unseen::cli
