// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The subcommands of the `unseen` binary, one file each. Each Add*Command adds its
// subcommand to `app`; its callback throws unseen::Error on bad input, which main()
// reports as "unseen: error: ..." with exit code 1.
#pragma once

#include <CLI/CLI.hpp>

namespace unseen::cli {

void AddVersionCommand(CLI::App& app);

}  // namespace unseen::cli
