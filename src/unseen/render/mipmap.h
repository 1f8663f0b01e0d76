// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Mip-map pyramids of UV textures for the rasterizer. A model seen from afar covers
// fewer pixels than its texture has texels; sampling the full-resolution texture then
// aliases (a camera averages over each pixel's footprint) and is slow (cache misses).
// Levels are built once per texture (2x2 area averages, like cv::pyrDown without the
// Gaussian) and kept in a small process-wide cache keyed by the texture's buffer and a
// fingerprint of its content.
//
// Textures are assumed not to be edited in place while they are in use: the fingerprint
// (a hash of 64 spread texels) catches a reused buffer holding another image, and most
// edits, but not an edit touching none of those texels. Replace a texture by a new
// cv::Mat (or call ClearMipmapCache()) after editing it.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace unseen {

// Levels of `texture` (CV_32FC3, non-empty): level 0 is `texture` itself, level k + 1
// halves level k (sizes rounded up) down to 1 px or 12 levels. Levels >= 1 are cached
// (the cache never keeps `texture` alive; at most 16 textures' levels). Thread-safe.
std::vector<cv::Mat> MipmapLevels(const cv::Mat& texture);

// Forgets every cached pyramid.
void ClearMipmapCache();

// The level for a texture mapped with `texels_per_pixel` texture pixels per image pixel
// (by area): floor(log2(texels_per_pixel) / 2), clamped to [0, num_levels - 1].
int MipmapLevelFor(double texels_per_pixel, int num_levels);

}  // namespace unseen
