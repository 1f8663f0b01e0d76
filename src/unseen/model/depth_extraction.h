// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Depth-map extraction (SPEC 5.1, thesis 3.1): a metric depth map seen from the reference
// camera of a rig, by one of three sources behind one interface, chosen by configuration:
//  * a multi-view plane sweep over every camera of the rig (the thesis's set-up);
//  * two-camera stereo: rectification and semi-global matching (OpenCV's StereoSGBM),
//    the depth carried back into the reference camera;
//  * a depth sensor: the frame's own depth image of the reference camera (RGB-D).
// Depth is only measured where the image has texture (or the sensor returns it); what is
// not measured stays 0, for the mesh generator to leave out, never interpolated.
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "unseen/camera/camera.h"
#include "unseen/io/sequence.h"

namespace unseen {

enum class DepthSourceKind { kPlaneSweep, kStereo, kSensor };

// "planesweep", "stereo", "sensor"; Parse throws unseen::Error naming the value.
std::string ToString(DepthSourceKind kind);
DepthSourceKind ParseDepthSourceKind(const std::string& text);

struct PlaneSweepOptions {
  // Fronto-parallel planes, uniform in inverse depth: at most `planes`, and no more than
  // make the farthest-seeing camera's match move `disparity_step_px` pixels from one plane
  // to the next across the depth range (the sub-plane fit does the rest); 0: always
  // `planes`.
  int planes = 64;
  double disparity_step_px = 0.0;
  int window_px = 7;  // side of the square window of the ZNCC cost
  // Cameras whose cost counts at each pixel: the best `best_share` of them, at least two
  // where there are (occlusion: a camera that sees something else there disagrees). All
  // by default: on periodic texture (a checker) every plane finds a few cameras that agree,
  // and only all the baselines together tell the true one (5-camera rig: 3 700 -> 7 500
  // pixels measured on the cube).
  double best_share = 1.0;
  double max_cost = 0.6;     // 1 - ZNCC above which a pixel stays unmeasured
  double uniqueness = 0.02;  // the best cost must beat every non-adjacent plane's by this
  // A measured pixel needs this many of the 24 around it (5x5) within 2 % of its depth:
  // isolated matches are mostly wrong.
  int min_support = 6;
  // The thesis's refinement: `refine_iterations` passes choosing, per pixel, the plane
  // minimising cost + smoothness * |plane - median of the 3x3 neighbours' planes|.
  int refine_iterations = 2;
  double smoothness = 0.02;
  // Coarse to fine over a pyramid of `levels` (1: every plane at full size): every
  // 2^(levels-1)-th plane at the coarsest level (with the smoothness passes there), then on
  // each finer level (every 2^l-th plane at level l) only the planes within `band_planes`
  // steps of that level's grid of the planes found at the 3x3 pixels about it one level up.
  int levels = 3;
  int band_planes = 4;
  // At the coarsest level, planes behind the depth range are swept too (at that level's
  // spacing, out to max_depth_m): a pixel that matches behind the range as well as inside
  // it (within `uniqueness`) is the background seen past the object, or ambiguous, and
  // stays unmeasured. Swept over the range alone, a
  // textured background finds some plane inside it that matches well enough and joins the
  // object at its depth (held-out three-camera rig before a butterfly photo: the model's
  // triangles ran down the photo's stripes).
  bool search_behind = true;
  int threads = 0;  // threads the sweep's tiles are spread over (the caller's included); 0: all
  void Check() const;
};

struct StereoOptions {
  int num_disparities = 256;  // at most, a multiple of 16 (OpenCV)
  int block_size = 5;         // odd, >= 3
  int uniqueness_ratio = 10;  // per cent
  int speckle_window = 100;   // px; 0 = no speckle filtering
  int speckle_range = 2;      // disparity units
  // The disparities searched reach past the object's depth band towards the background, up
  // to num_disparities in all: searched over the band alone, a background with a repeating
  // pattern (tiles, shelves, a chessboard) finds a wrong match inside it and joins the
  // object at its depth. Pixels matched outside the band are dropped either way.
  bool search_behind = true;
  std::string other_camera;   // the second camera; empty: the first that is not the reference
  void Check() const;
};

struct DepthExtractionOptions {
  DepthSourceKind source = DepthSourceKind::kPlaneSweep;
  double min_depth_m = 0.1;  // depth range searched / accepted
  double max_depth_m = 5.0;
  // Pixels whose texturedness (3.1) is below this are not measured by the image-based
  // sources (BGR in [0, 1]; a step of 0.1 in every channel across two pixels is 0.0075).
  double min_texturedness = 0.002;
  PlaneSweepOptions plane_sweep;
  StereoOptions stereo;
  void Check() const;
};

// A depth map of the reference camera.
struct DepthMap {
  cv::Mat depth;         // CV_32FC1 z in the reference camera, metres; 0 where not measured
  cv::Mat texturedness;  // CV_32FC1 (3.1) of the reference image inside the region measured
  // The source measures every surface in its range (a sensor), not only textured ones: a
  // pixel without depth there shows no surface in the range.
  bool dense = false;
  int ValidPixels() const;
};

// Texturedness (3.1): T(x, y) = sum over B, G, R of |grad I_c(x, y)|^2, central differences;
// `image` CV_32FC3 (or CV_8UC3, scaled to [0, 1]). Computed inside `roi` only (0 elsewhere;
// the whole image when empty): a model's region is a small part of a frame.
cv::Mat Texturedness(const cv::Mat& image, const PixelRect& roi = PixelRect());

// Camera `camera`'s image of `frame` as CV_32FC1 grey in [0, 1], checked against the rig
// (throws unseen::Error naming `source`, the camera and the frame when missing or
// mis-sized). For the sources.
cv::Mat GreyImage(const Frame& frame, const Rig& rig, int camera, const std::string& source);

// Calls fn(x, y, &depth) for every pixel of `roi` whose texturedness is at least
// `min_texturedness`, `depth` being that pixel of map->depth: where the image-based sources
// may measure. For the sources.
template <typename Fn>
void ForEachTexturedPixel(DepthMap* map, const PixelRect& roi, double min_texturedness, Fn&& fn) {
  const float min_t = static_cast<float>(min_texturedness);
  for (int y = roi.y0; y < roi.y1; ++y) {
    const float* tex = map->texturedness.ptr<float>(y);
    float* depth = map->depth.ptr<float>(y);
    for (int x = roi.x0; x < roi.x1; ++x) {
      if (tex[x] >= min_t) fn(x, y, depth + x);
    }
  }
}

class DepthSource {
 public:
  virtual ~DepthSource() = default;
  // The depth map of the reference camera from `frame` (images per rig camera, CV_32FC3 or
  // CV_8UC3; depths for the sensor), measured inside `roi` of the reference image (the
  // whole image when empty) and between near_m and far_m (the options' range when 0).
  // Throws unseen::Error naming the camera for missing or mis-sized images.
  virtual DepthMap Extract(const Frame& frame, const PixelRect& roi, double near_m = 0.0,
                           double far_m = 0.0) const = 0;
  virtual DepthSourceKind kind() const = 0;
};

// The source a rig calls for when none is chosen: its depth images (`has_depth`); else
// stereo for two cameras side by side looking about the same way (rectification and
// semi-global matching, which searches past the object's depth band); else the plane sweep
// over every camera (three or more, a pair stacked vertically, or a pair whose optical axes
// part by more than kMaxStereoConvergenceDeg: rectified, the views of a wide pair are
// sheared too far for block matching); kSensor for one camera without depth (which
// MakeDepthSource then refuses).
inline constexpr double kMaxStereoConvergenceDeg = 20.0;
DepthSourceKind NaturalDepthSource(const Rig& rig, int reference, bool has_depth);

// The source options.source for `rig` seen from camera `reference` (checked: the plane
// sweep needs two cameras or more, stereo two, with overlapping views).
std::unique_ptr<DepthSource> MakeDepthSource(const Rig& rig, int reference,
                                             const DepthExtractionOptions& options);

}  // namespace unseen
