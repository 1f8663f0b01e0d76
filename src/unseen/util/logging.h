// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Logging facade over spdlog. The library logs through these macros only; the
// command line sets the verbosity once with SetVerbosity().
#pragma once

#include <spdlog/spdlog.h>

namespace unseen {

// 0 = warnings and errors only, 1 = info (default), 2 = debug, 3 = trace.
void SetVerbosity(int level);

}  // namespace unseen

#define UNSEEN_LOG_TRACE(...) SPDLOG_TRACE(__VA_ARGS__)
#define UNSEEN_LOG_DEBUG(...) ::spdlog::debug(__VA_ARGS__)
#define UNSEEN_LOG_INFO(...) ::spdlog::info(__VA_ARGS__)
#define UNSEEN_LOG_WARN(...) ::spdlog::warn(__VA_ARGS__)
#define UNSEEN_LOG_ERROR(...) ::spdlog::error(__VA_ARGS__)
