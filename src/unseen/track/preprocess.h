// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Pre-processing of the virtual and the input image of one camera inside the region of
// interest, identically for both (SPEC 3.1 step 3): LINF (3.2, (4.11)), Gaussian blur
// (sigma = 1.8 px in the thesis), spatial gradients.
#pragma once

#include <opencv2/core.hpp>

namespace unseen {

struct PreprocessOptions {
  bool use_linf = true;          // LINF (4.11) before blurring
  // Standard deviation of LINF's wide Gaussian at pyramid level 0, pixels; divided by 2^level
  // at coarser levels (never below min_linf_sigma_px) so it covers the same part of the scene.
  double linf_sigma_px = 8.0;
  double min_linf_sigma_px = 4.0;
  double linf_epsilon = 0.05;    // eps_n of (4.11), intensity in [0, 1]
  double blur_sigma_px = 1.8;    // Gaussian blur, pixels of the level being processed [4.1.3]
  // Beyond the thesis: give the rendered object the input's low-frequency shading before
  // it is pasted (ratio of input to render low-passed over the object's pixels only, per
  // channel). LINF cannot equalise the silhouette's contrast, whose two sides are lit
  // differently; unequal contrast there biases the flow by a fraction of a pixel.
  bool shading_transfer = true;
  double shading_sigma_px = 4.0;  // at level 0, divided by 2^level (at least min_linf_sigma_px)
  // Camera images are gamma-encoded while a pixel integrates light linearly, so a pixel on
  // the silhouette is the gamma-encoded mix of object and background. The supersampled
  // virtual image mixes its silhouette pixels the same way (1 = mix the stored values).
  // Mixing the stored values instead shifts a silhouette against a bright background
  // outwards by a fraction of a pixel.
  double silhouette_gamma = 2.2;
  // The virtual image's outside within this many pixels of the rendered silhouette (at
  // every level) shows the background estimated from the input farther out (a normalized
  // Gaussian convolution of the input's pixels beyond the band, standard deviation
  // background_sigma_px), and so does the uncovered part of a silhouette pixel; 0: the
  // input itself. At the true pose the input's pixels beside the silhouette carry the
  // object's colour, blurred out by the camera's optics and compression: pasted as the
  // virtual image's outside they match the input exactly, while the object's own pixels
  // along the silhouette (the background blurred in) do not, and the mismatch pulls the
  // model smaller, away from the camera (a dim, dark object in noisy images: 7-10 mm at
  // the first frame). With the background estimated and PyramidOptions::rim_px 2, the
  // mismatch lies on both sides of the silhouette and cancels. Measured (band 2, rim 2, 125
  // benchmark runs and new renders; README, "The background beside the silhouette"): the
  // dim, noisy jeep 21.7 -> 100 %, the dim duck 94 -> 100 %, the real cube at 15/10/7.5 fps
  // over the whole sequence 82/84.8/80 -> 94/97/92 %, half the error on the zig-zag cube,
  // the 5-camera rig and the chequered box; but the duck behind the spider from perturbed
  // starts 100/84.4/97.8 -> 51.1/53.3/88.9 %, the fast cube on a background of its colours
  // 100 -> 86.7 %, the real cube from 33 starts 31.85 -> 29.22 (short runs through its
  // motion-blurred stretch). Not the default; for dim, noisy footage of a dark object.
  int background_band_px = 0;
  double background_sigma_px = 3.0;
  void Check() const;
  double ShadingSigmaAtLevel(int level) const;
  // LINF sigma at pyramid `level`, pixels of that level.
  double LinfSigmaAtLevel(int level) const;
};

// One pre-processed image: blurred (after LINF) CV_32FC3 and, when asked, its gradients.
struct PreprocessedImage {
  cv::Mat blurred;
  cv::Mat gx, gy;  // CV_32FC3, intensity per pixel (central differences)
};

// LINF (when enabled) + blur + (optionally) gradients of `image` (CV_32FC3 in [0, 1], a
// region of the level-`level` image). Outputs are reallocated only when their size changes.
void Preprocess(const cv::Mat& image, const PreprocessOptions& options, int level,
                bool with_gradients, PreprocessedImage* out);

}  // namespace unseen
