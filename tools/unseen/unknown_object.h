// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// What `unseen model` and `unseen track --unknown` share: the modeller's options from
// --config/--depth, and where the object is in the first frame (--init gt, --roi, --mask).
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/io/sequence.h"
#include "unseen/model/modeller.h"

namespace unseen::cli {

struct UnknownObjectArgs {
  std::string init;          // "gt", or empty
  std::string roi;           // "x,y,w,h" in the reference image, or empty
  std::string mask;          // mask image (non-zero = object), or empty
  std::string depth;         // planesweep | stereo | sensor; empty: the config's, else the
                             // sensor when the sequence has depth, the plane sweep otherwise
  std::string model_config;  // modeller options (YAML), or empty
};

// The modeller's options: the YAML file, with the depth source of --depth or the default
// for the sequence.
ModellerOptions ModellerOptionsFor(const UnknownObjectArgs& args, const Sequence& sequence,
                                   const std::string& command);

// Where the object is in frame `index` (already read as `frame`) and its object frame:
// --init gt takes the ground truth's frame; --roi and --mask the region (SPEC 4.4's frame
// unless --init gt). Throws unseen::Error naming the option for bad values, a mask of the
// wrong size, or a region with no depth.
struct ObjectStart {
  Rigid3d world_from_obj;
  PixelRect region;  // empty: the modeller's sphere about the origin
  cv::Mat mask;      // CV_8UC1 or empty
};
ObjectStart LocateUnknownObject(const UnknownObjectArgs& args, const Sequence& sequence, int index,
                                const Frame& frame, const Modeller& modeller,
                                const std::string& command);

// "x,y,w,h" (pixels) -> rectangle; throws naming `command` and the text.
PixelRect ParseRoi(const std::string& text, const std::string& command);

}  // namespace unseen::cli
