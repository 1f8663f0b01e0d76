// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The process's memory use, for long-run checks that it stays flat.
#pragma once

#include <cstdint>

namespace unseen {

// Resident set size of this process, bytes (Linux: /proc/self/statm); 0 where unknown.
int64_t ResidentMemoryBytes();

}  // namespace unseen
