// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// unseen: 6-DoF tracking of a priori unknown objects from calibrated cameras.
#include <cstdio>
#include <exception>

#include <CLI/CLI.hpp>
#include <opencv2/core/utility.hpp>

#include "tools/unseen/commands.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/memory.h"

int main(int argc, char** argv) {
  unseen::KeepFreedMemoryForReuse();
  CLI::App app{"unseen: track the 6-DoF pose of an object, known or never seen before, "
               "from one or more calibrated cameras."};
  app.require_subcommand(1);
  int verbosity = 1;
  app.add_flag("-v,--verbose", [&](int64_t n) { verbosity = 1 + static_cast<int>(n); },
               "More log output (-vv for trace)");
  app.add_flag("-q,--quiet", [&](int64_t) { verbosity = 0; }, "Warnings and errors only");
  app.parse_complete_callback([&] { unseen::SetVerbosity(verbosity); });

  unseen::cli::AddRegisteredCommands(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const unseen::Error& e) {
    std::fprintf(stderr, "unseen: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "unseen: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
