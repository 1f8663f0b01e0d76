// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Multi-view plane sweep (SPEC 5.1, thesis 3.1, in the spirit of Yang and Pollefeys):
// fronto-parallel planes of the reference camera, uniform in inverse depth; at each plane
// every other camera's image is warped into the reference view by the plane's homography
// H = K_j (R + t n^T / z) K_ref^-1 and compared by zero-mean normalised cross-correlation
// over a window; a pixel's cost at a plane is the mean of its best cameras' (occlusion
// robust). The winning plane is refined by the thesis's smoothness passes and to a
// fraction of a plane by a parabola through the neighbouring costs. Coarse to fine over an
// image pyramid by default: every fourth plane at quarter size, then on each finer level
// only a band of planes about what the level above found, in tiles of 32x32 pixels spread
// over threads.
#pragma once

#include "unseen/model/depth_extraction.h"

namespace unseen {

class PlaneSweepDepth : public DepthSource {
 public:
  // Throws unseen::Error for a rig of fewer than two cameras.
  PlaneSweepDepth(const Rig& rig, int reference, const DepthExtractionOptions& options);
  DepthMap Extract(const Frame& frame, const PixelRect& roi, double near_m = 0.0,
                   double far_m = 0.0) const override;
  DepthSourceKind kind() const override { return DepthSourceKind::kPlaneSweep; }

 private:
  Rig rig_;
  int reference_;
  DepthExtractionOptions options_;
};

}  // namespace unseen
