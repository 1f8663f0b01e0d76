// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Volumetric fusion in the object frame (beyond the thesis; SPEC 5.4's incremental
// modelling): a truncated signed distance field (Curless & Levoy 1996) on a dense voxel
// grid about the object's origin. Each depth map seen at a tracked pose is folded in as a
// running weighted average, so the surface grows with every side the cameras see while
// the noise of single maps averages out, and the object frame stays the one the first map
// fixed. The surface is read back as a triangle mesh by surface nets (one vertex per cell
// the zero level crosses, placed at the mean of its edge crossings; one quad per crossed
// grid edge): no case tables, watertight where observed, fewer triangles than marching
// cubes.
//
// Written here rather than taken from a library: the packages unseen may depend on have no
// CPU TSDF with mesh extraction (OpenCV's is in its contrib modules), and the integration
// is a hot loop over every voxel, written so the compiler vectorises the row.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/mesh/mesh.h"
#include "unseen/model/fusion_options.h"

namespace unseen {

struct TsdfIntegration {
  int updated_voxels = 0;  // voxels the map changed (surface band and carved)
  int surface_voxels = 0;  // of them, within the truncation band of the object's surface
};

class TsdfVolume {
 public:
  // A cube of half edge `half_extent_m` about `centre` (object frame, metres); the voxel is
  // max(min_voxel_m, 2 half_extent / voxels_per_side) and the grid shrinks to fit. Throws
  // unseen::Error for invalid options or a non-positive extent.
  TsdfVolume(const Eigen::Vector3f& centre, float half_extent_m, const TsdfOptions& options);

  // Folds in one depth map (CV_32FC1, metres along the optical axis, 0 = none) seen by
  // `camera` at `cam_from_obj`. `object_mask` (CV_8UC1 of the map's size, non-zero on the
  // object): its pixels measure the surface; the others only carve free space.
  // `support_plane` (optional, object frame, (n, d) with n.p + d = 0 and the object on the
  // positive side): the voxels in view within support_margin_m of it or below are free.
  // Throws unseen::Error for a map or mask of the wrong type or size.
  TsdfIntegration Integrate(const cv::Mat& depth, const cv::Mat& object_mask,
                            const PinholeCamera& camera, const Rigid3d& cam_from_obj,
                            const Eigen::Vector4f* support_plane = nullptr);

  // The zero level as a mesh in the object frame, counter-clockwise seen from outside
  // (the free side), with vertex normals; no triangles when nothing was seen yet.
  Mesh ExtractMesh() const;

  float voxel_m() const { return voxel_; }
  float truncation_m() const { return truncation_; }
  int size() const { return n_; }
  const Eigen::Vector3f& origin() const { return origin_; }  // centre of voxel (0, 0, 0)
  int integrations() const { return integrations_; }
  // Signed distance (in truncation units, + free) and weight of voxel (x, y, z).
  float Distance(int x, int y, int z) const { return tsdf_[Index(x, y, z)]; }
  float Weight(int x, int y, int z) const { return weight_[Index(x, y, z)]; }

 private:
  size_t Index(int x, int y, int z) const { return (size_t(z) * n_ + y) * n_ + x; }

  TsdfOptions options_;
  int n_ = 0;
  float voxel_ = 0.0f, truncation_ = 0.0f;
  Eigen::Vector3f origin_;
  std::vector<float> tsdf_, weight_;
  int integrations_ = 0;
};

}  // namespace unseen
