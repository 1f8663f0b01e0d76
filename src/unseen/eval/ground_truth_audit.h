// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Checks a sequence's ground truth against its measured depth. Ground truth of real footage
// comes from another measurement (a marker board, a motion-capture system) with errors of
// its own, worst in fast motion (blur, timing). Where the frames carry depth, the model
// rendered at the true pose must lie on the measured surface: the share of the model's
// pixels whose measured depth is within `agree_distance_m` of the rendered depth tells
// which frames' ground truth can be trusted to judge a tracker to the millimetre.
#pragma once

#include <string>
#include <vector>

#include "unseen/io/sequence.h"
#include "unseen/mesh/mesh.h"

namespace unseen {

struct GroundTruthAuditOptions {
  double agree_distance_m = 0.01;  // |measured - rendered depth| below this agrees, metres
  double min_agreement = 0.8;      // a frame is trusted at this share of agreeing pixels
  int min_pixels = 50;             // fewer model pixels with a measurement: not judged
  void Check() const;
};

struct GroundTruthAudit {
  GroundTruthAuditOptions options;
  std::vector<int> frames;         // frame ids with ground truth, sequence order
  // Per frame: share of the model's pixels (every camera with depth) whose measured depth
  // agrees with the rendered one, in [0, 1]; negative when the frame was not judged (no
  // depth, the model out of view or on too few measured pixels).
  std::vector<double> agreement;
  int judged = 0;                  // frames with an agreement
  int trusted = 0;                 // of those, at min_agreement or above

  bool Trusted(int index) const { return agreement[index] >= options.min_agreement; }
  // One line for people: judged, trusted, mean agreement.
  std::string Summary() const;
};

// Renders `model` (metres, object frame) at every frame's ground truth into each camera of
// `sequence` that has depth and compares with the measured depth. Throws unseen::Error when
// the sequence has no ground truth or no depth images; an unreadable frame is not judged.
GroundTruthAudit AuditGroundTruthWithDepth(const Sequence& sequence, const Mesh& model,
                                           const GroundTruthAuditOptions& options = {});

}  // namespace unseen
