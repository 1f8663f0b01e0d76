// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The interest-filter bank (SPEC 4.1, Figs. 2.3, 2.6): filters applied in order to an
// interest map of ones, each lowering it (2.4). Which filters, in which order and with
// what parameters comes from a YAML file, so an application tailors the bank without
// recompiling:
//
//   filters:
//     - type: motion          # MotionFilterOptions' fields
//       warmup_frames: 8
//     - type: colour          # colours_rgb: [[r, g, b], ...] in [0, 1], one radius each
//       colours_rgb: [[0.9, 0.2, 0.1]]
//       radii: [0.35]
//     - type: velocity        # moving along an image direction (x right, y down)
//       direction: [1, 0]
//       min_speed_px: 0.5
//       max_angle_deg: 45
//     - type: tracked_motion  # moving with the tracked object (model rebuilds)
//       max_difference_px: 1.0
//       relative_difference: 0.3
//       min_object_speed_px: 0.5
//     - type: position        # a world-frame box, metres
//       min_m: [-0.3, -0.3, 0.4]
//       max_m: [0.3, 0.3, 1.2]
//     - type: cooccurrence    # colour co-occurrence histogram (cooccurrence_filter.h)
//       reference_image: object.png   # required
//       reference_rect: [40, 30, 120, 90]  # x, y, width, height px; default: whole image
//       colours: 12           # and the other CooccurrenceFilterOptions fields
//     - type: recognition     # ORB + homography (recognition_filter.h)
//       reference_images: [front.png, side.png]  # required
//       reference_rects: [[0, 0, 200, 150], [10, 10, 80, 60]]  # optional, one per image
//       min_inliers: 12       # and the other FeatureRecognizerOptions fields
//
// Image paths are taken as given, or, when relative and the bank is loaded from a file
// (or given a folder), from that file's folder. Any other InterestFilter (another
// recogniser, say) is added with Add().
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "unseen/select/interest_filter.h"

namespace unseen {

class InterestFilterBank {
 public:
  void Add(std::unique_ptr<InterestFilter> filter);
  // The interest map (CV_32FC1, [0, 1]) of the frame after every filter, in order; each
  // judges only the pixels still above zero (a background model learns every frame).
  cv::Mat Apply(const FilterFrame& frame);
  // Every filter can judge (the background models have learnt their first frames).
  bool ready() const;
  int size() const { return static_cast<int>(filters_.size()); }
  const InterestFilter& filter(int i) const { return *filters_[i]; }

 private:
  std::vector<std::unique_ptr<InterestFilter>> filters_;
};

// The bank a YAML text describes (see above). Errors name `what`, the filter's index, the
// key and the value: unknown types and keys, values of the wrong type, invalid options,
// reference images that cannot be read. Relative image paths are resolved against
// `base_folder` unless it is empty.
InterestFilterBank ParseInterestFilterBank(const std::string& yaml_text, const std::string& what,
                                           const std::string& base_folder = "");
InterestFilterBank LoadInterestFilterBank(const std::string& path);

}  // namespace unseen
