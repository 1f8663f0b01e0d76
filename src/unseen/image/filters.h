// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Image filters of the tracker's pre-processing (SPEC 3.1 step 3, 3.2, 3.3), written to
// work on small regions of interest: every function takes and returns float images
// (CV_32FC1 or CV_32FC3, intensities nominally in [0, 1]) and replicates the border, so
// that two images of the same region are filtered identically.
#pragma once

#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"

namespace unseen {

// Wide Gaussian low-pass with standard deviation `sigma_px` (pixels, > 0). For wide
// kernels (sigma_px >= 4) the image is area-down-sampled by a power of two first, blurred
// there and bilinearly up-sampled, so the cost does not grow with sigma. Same type and
// size as `image`.
cv::Mat WideLowPass(const cv::Mat& image, double sigma_px);

// WideLowPass in two halves, for callers that combine low-passed images at the coarse
// scale and up-sample only the result: LowPassDown returns `image` area-down-sampled by
// `*factor` (the power of two WideLowPass would choose; 1 for narrow kernels) and blurred
// there; LowPassUp bilinearly brings such an image back to `size` (the original size).
// WideLowPass(image, s) == LowPassUp(LowPassDown(image, s, &f), image.size(), f).
cv::Mat LowPassDown(const cv::Mat& image, double sigma_px, int* factor);
cv::Mat LowPassUp(const cv::Mat& small, cv::Size size, int factor);

// LowPassDown's two steps, for a caller that area-down-samples by itself (summing only the
// pixels it has instead of building the whole image first): the factor LowPassDown
// chooses for an image of `size`, and the blur it gives the image down-sampled by it
// (whose pixels average `factor` x `factor` blocks of the image padded, border replicated,
// to a multiple of `factor`; factor 1: the image itself).
int LowPassFactor(cv::Size size, double sigma_px);
cv::Mat BlurDownsampled(const cv::Mat& small, double sigma_px, int factor);

// Local Illumination Normalization Filter, SPEC 3.2 (4.11), per channel:
//   I'(x, y) = 0.5 (I(x, y) + eps) / ((G * I)(x, y) + eps)
// with G a Gaussian of `sigma_px` pixels (WideLowPass) and `epsilon` the noise constant
// (intensity units, > 0). A region of constant colour becomes mid-grey 0.5; a gain or a
// smooth shading ramp is (nearly) removed. Same type and size as `image`.
cv::Mat LocalIlluminationNormalize(const cv::Mat& image, double sigma_px, double epsilon);

// Gaussian blur with standard deviation `sigma_px` (> 0), kernel of +-3 sigma, border
// replicated.
cv::Mat GaussianBlurred(const cv::Mat& image, double sigma_px);

// Central-difference gradients per channel in intensity per pixel:
//   gx(x, y) = (I(x+1, y) - I(x-1, y)) / 2,  gy likewise; one-sided at the border.
// `gx`, `gy` get the type and size of `image`.
void CentralGradients(const cv::Mat& image, cv::Mat* gx, cv::Mat* gy);

// Level-`level` pyramid pixels (each the mean of a 2^level x 2^level block of level-0
// pixels, the convention of PinholeCamera::PyramidLevel) of the rectangle `roi_at_level`
// (level pixels) of the level-0 image `image0`. `roi_at_level` must lie inside
// LevelRect(image0 size, level); throws unseen::Error otherwise.
cv::Mat DownsampledRegion(const cv::Mat& image0, int level, const PixelRect& roi_at_level);

// The rectangle of level-`level` pixels whose blocks lie entirely inside a level-0 image
// of `width0` x `height0` pixels: [0, width0 >> level) x [0, height0 >> level).
PixelRect LevelRect(int width0, int height0, int level);

}  // namespace unseen
