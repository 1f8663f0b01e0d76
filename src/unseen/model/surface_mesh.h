// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Mesh generation from one depth map (SPEC 5.2, thesis 3.2) and its projective texture
// (SPEC 5.3): the surface the reference camera sees of the object, in the object frame.
//  1. 3x3 median of the depth map (one-pixel spikes and pits);
//  2. texturedness (3.1) with 3x3 non-maximum suppression, and Harris corners;
//  3. a grid of boxes over the object's region: a box's vertex is its strongest Harris
//     corner, else the local texturedness maximum above min_texturedness closest to the
//     box centre, else (depth that needs no texture: a sensor's) the measured pixel
//     closest to the centre, else none; only pixels of the object's mask with depth;
//  4. the vertices lifted to 3-D by their depth and Delaunay-triangulated in the image;
//  5. vertices farther than max_radius_m from the object's origin dropped.
// Beyond the thesis: vertices along the mask's outline (SurfaceMeshOptions::
// contour_vertices); triangles outside the object's mask or spanning a depth
// discontinuity are dropped, so concave outlines do not pull in the background.
// The reference image textures the mesh as its projector (Mesh::projectors), with the
// mesh's depth seen from it.
#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/mesh/mesh.h"
#include "unseen/model/depth_extraction.h"

namespace unseen {

struct SurfaceMeshOptions {
  int median_px = 3;                // median filter of the depth map: 3 or 5 (1: none)
  int cell_px = 12;                 // side of a grid box, px (thesis: an m x n grid)
  double min_texturedness = 0.002;  // tau_T of (3.1) for a textured vertex
  double harris_k = 0.04;
  double harris_quality = 0.01;  // a corner's response over the region's strongest
  // Vertices where the depth map has depth but no texture (a depth sensor measures
  // textureless surfaces too); false for the image-based depth sources.
  bool untextured_vertices = false;
  // Beyond the thesis: vertices along the mask's outline too (where it has depth), so that
  // the mesh reaches the silhouette instead of stopping half a box inside it.
  bool contour_vertices = true;
  double max_radius_m = 0.0;  // step 5; 0: no limit
  // A triangle spans a depth discontinuity where the depth measured at its centroid or an
  // edge's midpoint is off its plane by more than this share of its depth.
  double max_depth_step = 0.02;
  double min_depth_step_m = 0.005;  // ... and by at least this much
  void Check() const;
};

struct SurfaceMeshReport {
  int candidate_vertices = 0;  // grid boxes with a vertex
  int dropped_far = 0;         // beyond max_radius_m
  int triangles_delaunay = 0;
  int dropped_outside = 0;          // triangles outside the mask
  int dropped_discontinuity = 0;    // triangles across a depth step
  int vertices = 0, triangles = 0;  // the mesh
};

// The mesh of the surface `camera` sees of the object inside `mask` (CV_8UC1, non-zero =
// object, the camera's size) from `depth_map`, vertices in the object frame given by
// `cam_from_obj`, textured by `image` (CV_32FC3, the camera's frame) as a projector.
// std::nullopt ("cannot model": fewer than three vertices or no triangle left), with the
// reason in `*why`. Throws unseen::Error for inputs of the wrong size or type.
std::optional<Mesh> BuildSurfaceMesh(const DepthMap& depth_map, const cv::Mat& image,
                                     const PinholeCamera& camera, const Rigid3d& cam_from_obj,
                                     const cv::Mat& mask, const SurfaceMeshOptions& options,
                                     SurfaceMeshReport* report = nullptr,
                                     std::string* why = nullptr);

}  // namespace unseen
