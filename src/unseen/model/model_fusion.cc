// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/model_fusion.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "unseen/mesh/decimate.h"
#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"
#include "unseen/util/timer.h"

namespace unseen {

ModelFusion::ModelFusion(const RigCamera& reference, double max_radius_m,
                         const ModelFusionOptions& options)
    : reference_(reference), max_radius_m_(max_radius_m), options_(options) {
  options_.Check();
  UNSEEN_CHECK(max_radius_m > 0.0 && std::isfinite(max_radius_m),
               "ModelFusion: the largest object radius {} m must be > 0", max_radius_m);
}

namespace {

// Direction from the object frame's origin to the projector's camera.
Eigen::Vector3d ViewDirection(const Projector& p) {
  return p.cam_from_obj.Inverse().translation().normalized();
}

// The depth map and object mask to fuse. A sparse map (the plane sweep measures textured
// pixels only) has the pixels of the build's mesh it lacks filled from the mesh, which
// interpolates them as the tracker sees the surface; a dense map (a depth sensor) is fused
// as measured.
void SurfaceDepth(const ModelBuild& build, const PinholeCamera& camera, const Rigid3d& cam_from_obj,
                  cv::Mat* depth, cv::Mat* mask) {
  if (build.depth.dense) {
    *depth = build.depth.depth;
    *mask = build.mask;
    return;
  }
  RenderOptions render;
  render.write_color = false;
  RenderBuffers seen;
  Render(*build.mesh, camera, cam_from_obj, camera.ImageRect(), render, &seen);
  *depth = build.depth.depth.clone();
  seen.depth.copyTo(*depth, (*depth <= 0.0f) & (seen.mask != 0));
  *mask = build.mask | seen.mask;
}

// Keeps the triangles a key view saw: the centre in front of it, inside its image, not
// behind the surface it saw there, the face turned towards it by more than `min_cos`.
// Elsewhere the surface's colour is unknown: drawn in a flat colour, its edge against the
// textured part would pull the tracker's photometric term; without it, the model ends
// where its texture ends, as a single build's does.
void KeepTexturedTriangles(double min_cos, Mesh* mesh) {
  std::vector<Eigen::Vector3d> projector_centres;  // in the object frame
  for (const Projector& p : mesh->projectors) {
    projector_centres.push_back(p.cam_from_obj.Inverse().translation());
  }
  std::erase_if(mesh->triangles, [&](const Eigen::Vector3i& t) {
    const Eigen::Vector3f& a = mesh->vertices[t[0]];
    const Eigen::Vector3f& b = mesh->vertices[t[1]];
    const Eigen::Vector3f& c = mesh->vertices[t[2]];
    const Eigen::Vector3d centre = ((a + b + c) / 3.0f).cast<double>();
    const Eigen::Vector3d normal = (b - a).cross(c - a).cast<double>().normalized();
    for (size_t i = 0; i < mesh->projectors.size(); ++i) {
      const Projector& p = mesh->projectors[i];
      const Eigen::Vector3d in_cam = p.cam_from_obj * centre;
      if (in_cam.z() <= 0.0) continue;
      const Eigen::Vector3d to_projector = projector_centres[i] - centre;
      if (normal.dot(to_projector.normalized()) < min_cos) continue;
      const Eigen::Vector2d px = p.camera.Project(in_cam);
      const int x = static_cast<int>(std::lround(px.x())),
                y = static_cast<int>(std::lround(px.y()));
      if (x < 0 || y < 0 || x >= p.camera.width || y >= p.camera.height) continue;
      const float seen = p.depth.empty() ? 0.0f : p.depth.at<float>(y, x);
      if (seen > 0.0f && in_cam.z() <= seen + p.depth_tolerance_m) return false;
    }
    return true;
  });
  mesh->RemoveUnusedVertices();
  mesh->ComputeNormals();
}

// Pixels of `camera`'s image the mesh covers at `cam_from_obj`.
double CoveredPixels(const Mesh& mesh, const PinholeCamera& camera, const Rigid3d& cam_from_obj) {
  RenderOptions render;
  render.write_color = false;
  RenderBuffers buffers;
  Render(mesh, camera, cam_from_obj, camera.ImageRect(), render, &buffers);
  return buffers.mask.empty() ? 0.0 : static_cast<double>(cv::countNonZero(buffers.mask));
}

}  // namespace

std::optional<Mesh> ModelFusion::Fuse(const ModelBuild& build, std::string* why) {
  UNSEEN_CHECK(build.ok() && !build.mesh->projectors.empty() && !build.mask.empty(),
               "ModelFusion: only a successful build (mesh, projector, mask) can be fused");
  Timer timer;
  const Rigid3d cam_from_obj = reference_.cam_from_world() * build.world_from_obj;
  if (!volume_) {
    float reach = 0.0f;
    for (const Eigen::Vector3f& v : build.mesh->vertices) reach = std::max(reach, v.norm());
    const float half_extent = std::min(static_cast<float>(max_radius_m_),
                                       static_cast<float>(options_.extent_factor) * reach);
    volume_.emplace(Eigen::Vector3f::Zero(), std::max(half_extent, 1e-3f), options_.volume);
    report_.voxel_mm = 1e3f * volume_->voxel_m();
  }
  cv::Mat depth, mask;
  SurfaceDepth(build, reference_.intrinsics, cam_from_obj, &depth, &mask);
  // The support plane in the object frame: n.(R p + t) + d = (R^T n).p + (n.t + d).
  std::optional<Eigen::Vector4f> support;
  if (build.segmentation.plane_found) {
    const Eigen::Vector3d n = build.segmentation.support_plane.head<3>();
    const Eigen::Vector3d n_obj = cam_from_obj.RotationMatrix().transpose() * n;
    support =
        Eigen::Vector4f(n_obj.x(), n_obj.y(), n_obj.z(),
                        n.dot(cam_from_obj.translation()) + build.segmentation.support_plane[3]);
  }
  report_.last = volume_->Integrate(depth, mask, reference_.intrinsics, cam_from_obj,
                                    support ? &*support : nullptr);
  ++report_.fused;

  // A key view for a direction not yet textured.
  const Projector& view = build.mesh->projectors.front();
  const Eigen::Vector3d direction = ViewDirection(view);
  const double min_cos = std::cos(options_.key_view_spacing_deg * M_PI / 180.0);
  const bool new_direction =
      std::none_of(key_views_.begin(), key_views_.end(),
                   [&](const Projector& k) { return ViewDirection(k).dot(direction) > min_cos; });
  const bool anchor = new_direction && static_cast<int>(key_views_.size()) < options_.max_key_views;
  if (anchor) key_views_.push_back(view);
  latest_view_.reset();
  if (!anchor && options_.latest_view) latest_view_ = view;

  Mesh mesh = volume_->ExtractMesh();
  report_.surface_triangles = mesh.num_triangles();
  if (mesh.triangles.empty()) {
    *why = "the fused volume holds no surface yet";
    report_.fuse_ms = timer.ElapsedMilliseconds();
    return std::nullopt;
  }
  DecimateOptions decimate;
  decimate.max_triangles = options_.max_triangles;
  decimate.max_error_m = options_.max_error_voxels * volume_->voxel_m();
  mesh = Decimate(mesh, decimate);
  // Each key view sees only its side: its depth of the fused surface hides the rest from it
  // (Projector::depth), so a point takes the colour of a view that saw it.
  RenderOptions render;
  render.write_color = false;
  mesh.projectors = key_views_;
  if (latest_view_) mesh.projectors.push_back(*latest_view_);
  for (Projector& p : mesh.projectors) {
    RenderBuffers seen;
    Render(mesh, p.camera, p.cam_from_obj, p.camera.ImageRect(), render, &seen);
    p.depth = seen.depth;
    p.depth_tolerance_m = std::max(0.003f, 1.5f * volume_->voxel_m());
  }
  KeepTexturedTriangles(std::cos(75.0 * M_PI / 180.0), &mesh);
  if (mesh.triangles.empty()) {
    *why = "no key view sees the fused surface";
    report_.fuse_ms = timer.ElapsedMilliseconds();
    return std::nullopt;
  }
  // Sparse depth leaves a few scattered voxels: their surface, a fraction of what the
  // build's own mesh covers in its image, is no model (ModelFusionOptions::min_coverage).
  const double covered = CoveredPixels(mesh, reference_.intrinsics, cam_from_obj);
  const double build_covers = CoveredPixels(*build.mesh, reference_.intrinsics, cam_from_obj);
  report_.coverage = build_covers > 0.0 ? covered / build_covers : 0.0;
  if (report_.coverage < options_.min_coverage) {
    *why = fmt::format(
        "the fused surface covers {:.0f} % of what the build's mesh covers in its image "
        "({:.0f} of {:.0f} px; fusion.min_coverage {:.2f}): too little depth was fused",
        100.0 * report_.coverage, covered, build_covers, options_.min_coverage);
    report_.fuse_ms = timer.ElapsedMilliseconds();
    return std::nullopt;
  }
  mesh.Check("fused model");
  report_.key_views = static_cast<int>(key_views_.size());
  report_.triangles = mesh.num_triangles();
  report_.fuse_ms = timer.ElapsedMilliseconds();
  return mesh;
}

}  // namespace unseen
