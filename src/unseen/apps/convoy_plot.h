// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// A picture of a convoy run (convoy.h), like the thesis's Figs. 4.27-4.30: on the left the
// top view of the lead's true path, the follower's path and the tracked lead positions; on
// the right, against time, the separation error, the tracking error (x, y) and the
// cross-track error, in units (mm).
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "unseen/apps/convoy.h"

namespace unseen {

struct ConvoyPlotOptions {
  int width_px = 1400;  // the whole picture
  int height_px = 800;
  void Check() const;
};

// The picture as CV_8UC3 BGR. Throws unseen::Error for a run without frames.
cv::Mat DrawConvoyPlot(const ConvoyResult& result, const ConvoyPlotOptions& options = {});

// DrawConvoyPlot written to `path` (PNG). Throws naming the file when it cannot be written.
void SaveConvoyPlot(const std::string& path, const ConvoyResult& result,
                    const ConvoyPlotOptions& options = {});

}  // namespace unseen
