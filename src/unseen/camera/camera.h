// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Pinhole cameras and rigs. Convention (SPEC 2): camera frame x right, y down, z along
// the optical axis; pixel coordinates have their origin at the centre of the top-left
// pixel, so pixel (u, v) covers [u - 0.5, u + 0.5] x [v - 0.5, v + 0.5].
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/types.hpp>

#include "unseen/geometry/rigid3.h"

namespace unseen {

// Integer pixel rectangle [x0, x1) x [y0, y1).
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  long area() const { return empty() ? 0 : long(width()) * height(); }
  PixelRect Intersect(const PixelRect& o) const;
  // Grows by `margin` pixels on every side.
  PixelRect Grow(int margin) const { return {x0 - margin, y0 - margin, x1 + margin, y1 + margin}; }
  bool operator==(const PixelRect&) const = default;
};

// The same rectangle as OpenCV's (x, y, width, height).
inline cv::Rect ToCvRect(const PixelRect& r) { return {r.x0, r.y0, r.width(), r.height()}; }

// Intrinsics of an undistorted pinhole camera plus its image size; optional OpenCV
// distortion coefficients [k1, k2, p1, p2, k3], removed once at input.
struct PinholeCamera {
  int width = 0;   // px
  int height = 0;  // px
  double fx = 0.0, fy = 0.0;  // focal lengths, px
  double cx = 0.0, cy = 0.0;  // principal point, px (pixel-centre convention)
  std::vector<double> distortion;  // OpenCV order; empty = none

  // A camera of `width` x `height` px with square pixels of focal length `focal_px` and the
  // principal point at the image centre ((width - 1) / 2, (height - 1) / 2), no distortion.
  static PinholeCamera Centered(int width, int height, double focal_px);

  // Throws unseen::Error naming `what` for non-positive size/focal length, NaN, or a
  // distortion vector whose length is not 4, 5, 8, 12 or 14.
  void Check(const std::string& what = "camera") const;

  Eigen::Matrix3d K() const;
  bool HasDistortion() const;

  // Pixel of a camera-frame point (z > 0 assumed; returns NaN otherwise).
  Eigen::Vector2d Project(const Eigen::Vector3d& p_in_cam) const;
  // Camera-frame point at depth z (metres along the optical axis) for a pixel.
  Eigen::Vector3d Unproject(const Eigen::Vector2d& pixel, double z) const;
  bool InImage(const Eigen::Vector2d& pixel) const;
  PixelRect ImageRect() const { return {0, 0, width, height}; }

  // The camera of pyramid level `level` (each level halves the resolution): intrinsics
  // scaled by 1/2^level with the pixel-centre convention kept (c' = (c + 0.5)/s - 0.5).
  PinholeCamera PyramidLevel(int level) const;
  // Same for an arbitrary down-sampling factor s (> 0), image size rounded up.
  PinholeCamera Scaled(double s) const;

  // Bounding rectangle of the projection of a sphere (centre in the camera frame, radius
  // r), SPEC 3.5 (4.16)-(4.21), clipped to the image. std::nullopt when the sphere lies
  // behind the camera or entirely outside the image. When the camera centre is inside the
  // sphere the whole image is returned.
  std::optional<PixelRect> SphereRect(const Eigen::Vector3d& centre_in_cam,
                                      double radius) const;
  // Bounding rectangle of the projections of `points_in_cam` (e.g. the corners of a box
  // around an object: then it bounds the object's projection), clipped to the image, with
  // SphereRect's pixel convention. std::nullopt for no points, a point not in front of the
  // camera (z < 1 mm; the rectangle would be unbounded) or a rectangle outside the image.
  std::optional<PixelRect> PointsRect(std::span<const Eigen::Vector3d> points_in_cam) const;
  // The same box of projections, not clipped to the image (image coordinates, pixel
  // centres at integers): std::nullopt for no points or a point not in front of the camera.
  struct Bounds {
    double x_min, x_max, y_min, y_max;
  };
  std::optional<Bounds> ProjectedBounds(std::span<const Eigen::Vector3d> points_in_cam) const;
};

// One camera of a synchronized rig.
struct RigCamera {
  std::string name;            // e.g. "cam0", the folder in a sequence
  PinholeCamera intrinsics;
  Rigid3d world_from_cam;
  Rigid3d cam_from_world() const { return world_from_cam.Inverse(); }
};

// Several synchronized cameras; one suffices.
struct Rig {
  std::vector<RigCamera> cameras;
  int size() const { return static_cast<int>(cameras.size()); }
  // Index of the camera called `name`, or -1.
  int Find(const std::string& name) const;
  void Check() const;
};

}  // namespace unseen
