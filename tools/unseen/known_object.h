// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// `--init auto` for a known model (SPEC 4.5): where the object is in the reference camera
// (--roi, or the region of one motion (motion_segmentation.h) that the interest filter
// bank selects, frame by frame) and its pose there (select/known_model_pose.h).
#pragma once

#include <string>

#include "unseen/io/sequence.h"
#include "unseen/select/known_model_pose.h"
#include "unseen/track/tracker.h"

namespace unseen::cli {

struct KnownObjectStart {
  int index = -1;             // frame index (0-based) where tracking starts
  Frame frame;                // that frame
  KnownModelPoseResult pose;  // the tracker is initialised at its pose
};

// With `roi` ("x,y,w,h"): the pose at frame `first_frame` from that box, or an error when
// none is confident. Without: the interest filter bank of `filters` (YAML; empty: motion
// alone) learns from frame 0 on, and from `first_frame` on each frame with a selected
// region is tried until a pose is found (an error when none is by the last frame).
// Errors name `command`.
KnownObjectStart FindKnownObject(const Sequence& sequence, int first_frame, const std::string& roi,
                                 const std::string& filters, Tracker* tracker,
                                 const std::string& command);

}  // namespace unseen::cli
