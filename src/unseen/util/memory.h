// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The process's memory use, for long-run checks that it stays flat, and the allocator's
// handling of the large blocks freed from frame to frame.
#pragma once

#include <cstdint>

namespace unseen {

// Resident set size of this process, bytes (Linux: /proc/self/statm); 0 where unknown.
int64_t ResidentMemoryBytes();

// Keeps the large blocks that a frame frees (images, render buffers, pyramid levels:
// megabytes each, of a new size at every round as the object's region moves) in the heap for
// the next frame, instead of returning each to the system and faulting its pages in anew
// (glibc: blocks up to the 32 MB maximum of M_MMAP_THRESHOLD come from the heap, and the heap
// is trimmed past 256 MB of free memory at its top). Page faults were a quarter of the
// tracking time of an object covering a 640x480 frame. A process-wide setting: the
// command-line tool and the benchmarks make it first thing; an application embedding the
// tracker may. False where it does not apply (not glibc) or was refused.
bool KeepFreedMemoryForReuse();

}  // namespace unseen
