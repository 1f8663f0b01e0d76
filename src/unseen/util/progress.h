// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <cstdio>
#include <string>

#include "unseen/util/timer.h"

namespace unseen {

// A progress line on stderr for long runs: frames done, frames per second, ETA.
// Redraws in place at most every `min_interval_s`; silent when disabled.
class ProgressLine {
 public:
  ProgressLine(std::string label, int total, bool enabled = true,
               double min_interval_s = 0.5);
  ~ProgressLine();

  // Marks `done` items finished (absolute count).
  void Update(int done);
  // Prints the final line and a newline (idempotent).
  void Finish();

  // "12/300 frames, 45.1 fps, ETA 6 s" for the given state.
  static std::string Format(const std::string& label, int done, int total,
                            double elapsed_s);

 private:
  std::string label_;
  int total_;
  bool enabled_;
  double min_interval_s_;
  int done_ = 0;
  double last_print_s_ = -1.0;
  bool finished_ = false;
  Timer timer_;
};

}  // namespace unseen
