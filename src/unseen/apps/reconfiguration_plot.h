// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// A picture of a camera-reconfiguration run (SPEC 7.2): the top view for the run on true
// poses and the run on tracked poses side by side (columns, the object's true and tracked
// paths, the reconfigurable cameras' positions and fields of view at regular frames, as in
// the thesis's Fig. 5.15), and below, per camera, the visibility (5.1) over time for the
// tracked, true and fixed runs (Fig. 5.17).
#pragma once

#include <opencv2/core.hpp>

#include "unseen/apps/camera_reconfiguration.h"

namespace unseen {

struct ReconfigurationPlotOptions {
  int top_view_px = 600;         // side of each top-view panel, px
  int curve_height_px = 170;     // height of each camera's visibility panel, px
  int camera_every_frames = 36;  // cameras drawn every this many frames (Fig. 5.15: 36)
  double ray_length_m = 0.35;    // length of the drawn field-of-view edges
  void Check() const;
};

// The plot as a CV_8UC3 BGR image. Throws for a result without frames.
cv::Mat DrawReconfigurationPlot(const ReconfigurationConfig& config,
                                const ReconfigurationResult& result,
                                const ReconfigurationPlotOptions& options = {});

}  // namespace unseen
