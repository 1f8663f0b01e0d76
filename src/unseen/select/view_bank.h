// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Orientation of a known model from its appearance in one image square (SPEC 4.5, thesis
// 2.2.2 and App. A): the model is rendered from many directions, each render turned
// through several in-plane angles, and each view cut to the square around its silhouette
// and shrunk to a small patch; the input square is compared with every patch.
//
// The thesis projected grey patches into a PCA basis of its 288 views and took the
// nearest. Here each view is scored by two cues that do not depend on what surrounds the
// object in the input, and that an occluder spoils only where it covers the object:
//  * appearance: an ordinal comparison of grey levels inside the view's silhouette: for
//    every pair of neighbouring pixels (right, below) inside it, whether the input's grey
//    level steps up or down where the view's does; a step counts fully from
//    `appearance_step` times the box's mean step, smaller ones in proportion (a gain and an
//    offset of the image do not change it; a model without texture scores 0 here). A
//    correlation of grey levels, the earlier cue, lets one bright occluder inside the box
//    dominate the whole sum: with a white bar across a third of the box the true view fell
//    to rank 300-2 500 of 4 800;
//  * silhouette: how strongly the input's gradient runs across the view's outline,
//    (g . n)^2 summed over the outline (n its normal) relative to |g|^2 over the patch,
//    with every gradient saturated first (a magnitude of `gradient_saturation` times the
//    patch's mean counts half as much as an infinitely strong one), so that an occluder's
//    or a background's few strong edges do not outweigh the object's outline (what lets an
//    untextured model be oriented at all).
// Both are sums of products of an input image with a view image fixed at construction,
// so each view costs five dot products of patch_px^2 floats: scoring every one of the
// 4 800 default views exhaustively takes a few milliseconds, less than the thesis's PCA
// would save, and exact (a PCA basis of the views cannot express a comparison masked by
// each view's own silhouette). Renders come from render/rasterizer.h without shading.
#pragma once

#include <atomic>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/mesh/mesh.h"

namespace unseen {

struct ViewBankOptions {
  int num_directions = 300;  // viewing directions, spread evenly over the sphere (Fibonacci)
  int num_rolls = 16;        // in-plane angles per direction, 360 / num_rolls degrees apart
  int patch_px = 32;         // side of the compared patches, pixels
  int render_px = 128;       // side of the render each direction's views are cut from
  // Weight of the silhouette cue in the score, (1 - weight) that of the appearance cue.
  double silhouette_weight = 0.4;
  // The input's grey-level step between neighbours that counts as a full step up or down,
  // times the mean step over the box's square (smaller steps count in proportion).
  double appearance_step = 1.0;
  // Input gradient magnitude, times the square's mean, at which the silhouette cue counts
  // a gradient half as much as an infinitely strong one: g / (1 + |g| / s).
  double gradient_saturation = 0.3;
  int threads = 0;  // the directions are rendered on this many threads; 0: every core
  void Check() const;
};

// A view's orientation and where its silhouette sits, to turn a match into a pose.
struct ViewMatch {
  int view = -1;
  double score = 0.0;       // (1 - w) * appearance + w * silhouette, in [-1, 1]
  double appearance = 0.0;  // ordinal agreement inside the silhouette, [-1, 1]
  double silhouette = 0.0;  // outline gradient share mapped to [-1, 1]
  Eigen::Quaterniond cam_from_obj_rotation = Eigen::Quaterniond::Identity();
};

class ViewBank {
 public:
  // Renders `model` (metres, object frame; Mesh::Check()) from every direction. Throws
  // unseen::Error for invalid options or a model that covers no pixel, and when `cancel`
  // (if given) turns true before every direction is rendered (the rest are skipped).
  explicit ViewBank(const Mesh& model, const ViewBankOptions& options = {},
                    const std::atomic<bool>* cancel = nullptr);

  int size() const { return static_cast<int>(views_.size()); }
  const ViewBankOptions& options() const { return options_; }

  // Scores every view against the square of `image` (CV_32FC3 BGR [0, 1] or CV_8UC3)
  // around the object's bounding box `box` (pixels; the square has the box's centre and
  // its longer side; parts outside the image count as black) and returns up to
  // `max_matches` views, best first, no two closer than `min_separation_deg` in rotation.
  // Throws unseen::Error for an empty box or an image of another type.
  std::vector<ViewMatch> Match(const cv::Mat& image, const PixelRect& box, int max_matches,
                               double min_separation_deg) const;

  // The pose of the object in a camera (`intrinsics`) whose image shows it, in the view
  // `match`, with its silhouette's bounding box `box`: the view's orientation, turned so
  // that the object sits on the ray through the box's centre; the depth from the ratio of
  // the silhouette's size in the view and in the image.
  Rigid3d CamFromObj(const ViewMatch& match, const PinholeCamera& intrinsics,
                     const PixelRect& box) const;

 private:
  struct View {
    Eigen::Quaterniond cam_from_obj_rotation;
    // The silhouette's bounding square in the render: centre minus principal point and
    // side, render pixels.
    Eigen::Vector2d centre_offset_px;
    double side_px = 0.0;
  };

  ViewBankOptions options_;
  Eigen::Vector3d sphere_centre_ = Eigen::Vector3d::Zero();  // object frame, metres
  double render_focal_px_ = 0.0;
  double render_distance_m_ = 0.0;  // of the sphere's centre from the render camera
  std::vector<View> views_;
  // One row per view, patch_px^2 columns each: the view's grey-level steps to the right
  // and downward neighbour inside the silhouette (each in [-1, 1], together summing to 1 in
  // absolute value, zero elsewhere), and the outline weights times nx^2, 2 nx ny and ny^2.
  using ViewRows = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  ViewRows step_right_, step_down_, outline_xx_, outline_xy_, outline_yy_;
  std::vector<float> outline_weight_;
};

// `n` unit vectors spread evenly over the sphere (the Fibonacci lattice).
std::vector<Eigen::Vector3d> FibonacciSphere(int n);

}  // namespace unseen
