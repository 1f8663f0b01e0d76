// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The virtual image (SPEC 3.1 step 2): the model rendered at a pose into a region of one
// camera's pyramid level and composed over the input, so that its pixels compare with the
// input's. Supersampled renders are area-averaged 2x2; where a pixel is partly covered, the
// part not covered shows the background estimated from the neighbouring uncovered input
// pixels (at the true pose the input's own pixel there already mixes in the object, which
// would bias the silhouette), mixed in linear light with the camera's gamma. Optionally the
// shading the model lacks is transferred from the input (PreprocessOptions).
#pragma once

#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/mesh/mesh.h"
#include "unseen/render/rasterizer.h"
#include "unseen/track/preprocess.h"
#include "unseen/util/thread_pool.h"

namespace unseen {

// Buffers of the size of the region, reused from round to round.
struct VirtualImage {
  cv::Mat composite;  // CV_32FC3 BGR [0, 1]: the input with the render over it
  cv::Mat mask;       // CV_8UC1 255 where any sample of the pixel is covered
  cv::Mat depth;      // CV_32FC1 camera-frame z, metres: mean of the covered samples; 0 else
  cv::Mat coverage;   // CV_8UC1 covered samples of 4 (a render without supersampling: 0 or 4)
  RenderBuffers render;  // the render's own buffers
};

// Renders `model` seen from `camera` (the level's) at `cam_from_obj` inside `render_rect`
// (level pixels; empty: all of `roi`), 2x2 supersampled or not, and composes it over
// `input_roi` (CV_32FC3, the input inside `roi`) into `out`. Adds the render's and the
// composition's milliseconds to `render_ms` and `compose_ms`. `pool` (may be null) runs the
// render's shading pass. False when nothing of the region was rendered.
bool ComposeVirtualImage(const Mesh& model, const PinholeCamera& camera,
                         const Rigid3d& cam_from_obj, const PixelRect& roi,
                         const PixelRect& render_rect, const cv::Mat& input_roi, bool supersample,
                         const PreprocessOptions& options, int level, ThreadPool* pool,
                         VirtualImage* out, double* render_ms, double* compose_ms);

// Multiplies the rendered colour of `out`'s composite by the low-frequency ratio of input to
// render over the fully covered pixels (PreprocessOptions::shading_transfer at `level`).
// `rendered`: the part of the region the render covers pixels of (none outside it).
void TransferShading(const cv::Mat& input_roi, const PreprocessOptions& options, int level,
                     const cv::Rect& rendered, VirtualImage* out);

}  // namespace unseen
