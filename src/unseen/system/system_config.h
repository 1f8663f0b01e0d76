// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Everything the complete system (system.h) is configured by, in one YAML file
// (`unseen run --config system.yaml`), so an application tailors it without recompiling:
//
//   system:                      # SystemOptions
//     regions: motion            # motion (segmentation) or interest (the map's parts)
//     reselect_after_lost_frames: 10
//     rebuild_from_tracked_motion: true  # rebuilds: the pixels moving with the object select it
//   filters:                     # the interest filter bank (interest_filter_bank.h)
//     - type: motion
//       warmup_frames: 8
//   segmentation: {block_px: 8, min_motion_px: 0.25}      # MotionSegmentationOptions
//   selection: {min_interest_share: 0.05}                  # RegionSelectionOptions
//   known_pose: {max_candidates: 12, min_confidence: 0.5}  # KnownModelPoseOptions
//   update: {mode: incremental, every_frames: 30}          # ModelUpdateOptions
//   tracked_motion: {max_difference_px: 1.0}              # TrackedMotionFilterOptions
//   tracker: tracker.yaml        # TrackerOptions file, relative to this file
//   modeller: model.yaml         # ModellerOptions file, relative to this file
//
// Every section and key is optional; what is absent keeps its default. configs/system/
// holds commented examples.
#pragma once

#include <optional>
#include <string>

#include "unseen/model/modeller.h"
#include "unseen/select/interest_filter_bank.h"
#include "unseen/system/system.h"
#include "unseen/track/tracker_options.h"

namespace unseen {

struct SystemConfig {
  SystemOptions system;
  std::optional<InterestFilterBank> filters;  // when the file lists them
  TrackerOptions tracker;
  std::optional<ModellerOptions> modeller;  // when the file names a modeller file
  std::string source;                       // the file (or text label) it came from
};

// "motion" or "interest"; throws unseen::Error naming `where` for anything else.
RegionSource ParseRegionSource(const std::string& text, const std::string& where);

// The configuration `yaml_text` describes; relative paths are resolved against
// `base_dir`. Errors name `what`, the section, the key and the value (unknown sections
// and keys, values of the wrong type, options whose Check() fails).
SystemConfig ParseSystemConfig(const std::string& yaml_text, const std::string& what,
                               const std::string& base_dir = ".");
SystemConfig LoadSystemConfig(const std::string& path);

}  // namespace unseen
