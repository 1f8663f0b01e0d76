// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// A generated cluttered background, standing in for the thesis's photo of a laboratory
// (SPEC 8 "a photo as cluttered background") when no image file is given: shelves, boxes,
// posters with text, cables, blobs and fine texture over a lit wall, at many scales and
// in many colours, so that it has the strong edges and texture that distract a tracker.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>

namespace unseen {

// A `width` x `height` CV_32FC3 BGR image in [0, 1], a deterministic function of the
// arguments (std::mt19937 seeded from `seed`; no OpenCV RNG). Throws unseen::Error for a
// size below 16 px.
cv::Mat MakeClutterImage(int width, int height, uint64_t seed);

}  // namespace unseen
