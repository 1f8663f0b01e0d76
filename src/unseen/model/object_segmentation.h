// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Segmenting the object of interest for modelling (SPEC 5.5, thesis 3.5): which pixels of
// the reference image may give the model vertices. The region (the selected region R, or
// at a rebuild the rectangle of the object's bounding sphere at the tracked pose) and an
// optional mask (the thresholded interest map, or any mask image) bound it; measured depth
// narrows it to the object: within max_radius_m of the object's origin (a position
// interest filter), off the dominant plane that reaches the region's rim (the table or
// floor the object stands on), and connected in depth to the surface nearest the origin
// (not a neighbouring object, not a wrong match on the background, not a sensor's island
// of a few pixels); where the depth is
// sparse (image-based sources) across small gaps, the area around those pixels.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/model/depth_extraction.h"

namespace unseen {

struct SegmentationOptions {
  double max_radius_m = 0.15;  // the object's extent around its origin
  bool remove_support_plane = true;
  double plane_tolerance_m = 0.006;  // a pixel this close to the support plane is on it ...
  double plane_normal_deg = 25.0;    // ... if its surface normal is this close to the plane's
  int plane_iterations = 200;        // RANSAC hypotheses
  double min_plane_share = 0.15;     // the plane holds at least this share of the pixels
  // Neighbouring pixels are connected when their depths differ by less than this share
  // of the depth; the connectivity applies to dense depth maps (DepthMap::dense) and where
  // at least dense_share of the region's pixels have depth.
  double max_depth_step = 0.03;
  double dense_share = 0.5;
  // Dense depth: the object is the connected surface nearest the origin among those
  // holding at least this share of the measured pixels within max_radius_m (a sensor's
  // noise and lost pixels leave small islands, which may lie nearer the origin), or of a
  // selecting mask's (MaskRole::kSelects).
  double min_component_share = 0.05;
  // Dense depth whose surfaces (components of at least min_component_share, as above) hold
  // less than this share of the measured pixels left (within the radius, off the plane)
  // measures the object only in scattered pixels (a sensor far from it, a dark object:
  // noise and lost pixels thin it out into islands): its pixels then connect across gaps
  // as sparse depth's do.
  double min_connected_share = 0.3;
  // Sparse depth: measured pixels connect across gaps of up to this many pixels, and the
  // object's area reaches this far around them.
  int sparse_gap_px = 8;
  int sparse_fill_px = 6;
  void Check() const;
};

struct SegmentationReport {
  int region_pixels = 0, with_depth = 0, on_plane = 0, beyond_radius = 0, unconnected = 0;
  bool plane_found = false, dense = false;
  bool fragmented = false;  // dense depth taken as sparse (min_connected_share)
  // What a report line adds when the depth was fragmented: "" or a note saying so.
  const char* FragmentedNote() const {
    return fragmented ? " (dense depth in islands: joined as sparse)" : "";
  }
  // When plane_found: the support plane in the camera frame, (n, d) with n.p + d = 0, |n|
  // = 1, the object frame's origin on the positive side.
  Eigen::Vector4d support_plane = Eigen::Vector4d::Zero();
};

// What a given mask says about the object's pixels.
enum class MaskRole {
  kBounds,   // the object lies within the mask (a user's mask, an interest map's part)
  // The object holds some of the mask's pixels (the blocks that moved: an untextured
  // object moves in those along its outline only, and those hold the background's side
  // too): the connected surfaces holding min_component_share of the mask's measured pixels
  // are the candidates, the object's reaches beyond the mask. Dense depth (a sensor's): the
  // candidate nearest the origin; sparse depth: the largest near it (as without a mask).
  kSelects,
};

// CV_8UC1 of the camera's size, 255 on the object's pixels. `origin_in_cam`: the object
// frame's origin in the camera (inside or just behind the visible surface); `given_mask`
// (empty: none) CV_8UC1, non-zero on object pixels as `mask_role` says. Deterministic
// (seeded RANSAC).
cv::Mat SegmentObject(const DepthMap& depth_map, const PinholeCamera& camera,
                      const PixelRect& region, const Eigen::Vector3d& origin_in_cam,
                      const cv::Mat& given_mask, const SegmentationOptions& options,
                      SegmentationReport* report = nullptr,
                      MaskRole mask_role = MaskRole::kBounds);

}  // namespace unseen
