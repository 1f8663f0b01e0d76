// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/util/logging.h"

#include <spdlog/sinks/stdout_color_sinks.h>

namespace unseen {

void SetVerbosity(int level) {
  static const bool initialised = [] {
    // Logs go to stderr so that stdout stays clean for machine-readable output.
    auto logger = spdlog::stderr_color_mt("unseen");
    logger->set_pattern("[%H:%M:%S.%e] [%^%l%$] %v");
    spdlog::set_default_logger(logger);
    return true;
  }();
  (void)initialised;
  switch (level) {
    case 0: spdlog::set_level(spdlog::level::warn); break;
    case 1: spdlog::set_level(spdlog::level::info); break;
    case 2: spdlog::set_level(spdlog::level::debug); break;
    default: spdlog::set_level(spdlog::level::trace); break;
  }
}

}  // namespace unseen
