// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/util/progress.h"

#include <fmt/format.h>

namespace unseen {

ProgressLine::ProgressLine(std::string label, int total, bool enabled,
                           double min_interval_s)
    : label_(std::move(label)),
      total_(total),
      enabled_(enabled),
      min_interval_s_(min_interval_s) {}

ProgressLine::~ProgressLine() { Finish(); }

std::string ProgressLine::Format(const std::string& label, int done, int total,
                                 double elapsed_s) {
  const double rate = elapsed_s > 0.0 ? done / elapsed_s : 0.0;
  std::string line = fmt::format("{} {}/{} frames, {:.1f} fps", label, done, total, rate);
  if (rate > 0.0 && done < total) {
    line += fmt::format(", ETA {:.0f} s", (total - done) / rate);
  }
  return line;
}

void ProgressLine::Update(int done) {
  done_ = done;
  if (!enabled_ || finished_) return;
  const double now = timer_.ElapsedSeconds();
  if (last_print_s_ >= 0.0 && now - last_print_s_ < min_interval_s_) return;
  last_print_s_ = now;
  std::fprintf(stderr, "\r%s   ", Format(label_, done_, total_, now).c_str());
  std::fflush(stderr);
}

void ProgressLine::Finish() {
  if (finished_) return;
  finished_ = true;
  if (!enabled_ || last_print_s_ < 0.0) return;
  std::fprintf(stderr, "\r%s   \n",
               Format(label_, done_, total_, timer_.ElapsedSeconds()).c_str());
}

}  // namespace unseen
