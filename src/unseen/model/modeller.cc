// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/modeller.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "unseen/image/image_io.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/timer.h"

namespace unseen {

Modeller::Modeller(const Rig& rig, int reference, const ModellerOptions& options)
    : rig_(rig), reference_(reference), options_(options) {
  options_.Check();
  UNSEEN_CHECK(reference_ >= 0 && reference_ < rig_.size(),
               "Modeller: reference camera {} not in a rig of {} cameras", reference_, rig_.size());
  source_ = MakeDepthSource(rig_, reference_, options_.depth);
  if (options_.depth.source == DepthSourceKind::kPlaneSweep &&
      options_.initial_pose_planes > options_.depth.plane_sweep.planes) {
    DepthExtractionOptions whole_range = options_.depth;
    whole_range.plane_sweep.planes = options_.initial_pose_planes;
    initial_pose_source_ = MakeDepthSource(rig_, reference_, whole_range);
  }
  if (options_.mesh.max_radius_m <= 0.0) {
    options_.mesh.max_radius_m = options_.segmentation.max_radius_m;
  }
  // A depth sensor measures textureless surfaces too: vertices need no texture there.
  if (options_.depth.source == DepthSourceKind::kSensor) options_.mesh.untextured_vertices = true;
}

ModelBuild Modeller::Build(const Frame& frame, const Rigid3d& world_from_obj,
                           const PixelRect& region, const cv::Mat& mask,
                           const Mesh* current, MaskRole mask_role) const {
  UNSEEN_CHECK(world_from_obj.IsValid(), "Modeller: object frame {} is not a valid pose",
               world_from_obj.ToString());
  const RigCamera& ref = rig_.cameras[reference_];
  const PinholeCamera& camera = ref.intrinsics;
  UNSEEN_CHECK(mask.empty() || (mask.type() == CV_8UC1 && mask.cols == camera.width &&
                                mask.rows == camera.height),
               "Modeller: mask is {}x{} type {}; expected {}x{} CV_8UC1", mask.cols, mask.rows,
               mask.type(), camera.width, camera.height);
  ModelBuild out;
  out.world_from_obj = world_from_obj;
  Rigid3d cam_from_obj = ref.cam_from_world() * world_from_obj;
  const Eigen::Vector3d origin = cam_from_obj.translation();
  const double radius = options_.segmentation.max_radius_m;
  if (origin.z() <= 0.0) {
    out.why = "the object frame's origin is behind the reference camera";
    return out;
  }
  out.region = region;
  if (out.region.empty()) {
    const std::optional<PixelRect> sphere = camera.SphereRect(origin, radius);
    if (!sphere) {
      out.why = "the object is outside the reference camera's view";
      return out;
    }
    out.region = *sphere;
  }
  const PixelRect given = out.region;
  out.region = out.region.Intersect(camera.ImageRect());
  // A given region mostly beyond the image (kMinRegionInside); the bounding sphere's
  // rectangle, which has slack, is not judged.
  const double inside = ShareInside(given, camera);
  if (!region.empty() && inside < kMinRegionInside) {
    out.why = fmt::format(
        "the object's region (x {} y {} w {} h {}) lies {:.0f} % outside the {}x{} reference "
        "image: an object cut by the image border cannot be modelled",
        given.x0, given.y0, given.width(), given.height(), 100.0 * (1.0 - inside), camera.width,
        camera.height);
    return out;
  }
  if (out.region.width() < 8 || out.region.height() < 8) {
    out.why = "the object's region is smaller than 8x8 pixels in the reference image";
    return out;
  }
  // An image-based source needs a second view of the object.
  if (options_.depth.source != DepthSourceKind::kSensor) {
    bool seen_twice = false;
    for (int c = 0; c < rig_.size() && !seen_twice; ++c) {
      if (c == reference_) continue;
      const RigCamera& other = rig_.cameras[c];
      const Eigen::Vector3d in_other = other.cam_from_world() * (world_from_obj.translation());
      seen_twice = other.intrinsics.SphereRect(in_other, radius).has_value();
    }
    if (!seen_twice) {
      out.why = fmt::format(
          "no camera but the reference sees the object (the rig's views do not overlap "
          "there); depth source {} needs two views of it",
          ToString(options_.depth.source));
      return out;
    }
  }
  Timer timer;
  const double near = std::max(options_.depth.min_depth_m, origin.z() - radius);
  const double far = std::min(options_.depth.max_depth_m, origin.z() + radius);
  if (!(far > near)) {
    out.why = "the object lies outside the depth range";
    return out;
  }
  out.depth = source_->Extract(frame, out.region, near, far);
  out.depth_ms = timer.ElapsedMilliseconds();
  timer.Restart();
  if (out.depth.ValidPixels() < 3) {
    out.why = fmt::format("no depth measured in the object's region (source {})",
                          ToString(options_.depth.source));
    return out;
  }
  out.mask = SegmentObject(out.depth, camera, out.region, origin, mask, options_.segmentation,
                           &out.segmentation, mask_role);
  {
    const SegmentationReport& sr = out.segmentation;
    UNSEEN_LOG_DEBUG(
        "modeller: segmentation of {} region pixels: {} with depth, {} on the support plane "
        "(found {}), {} beyond the radius, {} unconnected{}; {} on the object",
        sr.region_pixels, sr.with_depth, sr.on_plane, sr.plane_found, sr.beyond_radius,
        sr.unconnected, sr.FragmentedNote(),
        cv::countNonZero(out.mask));
  }
  const cv::Mat image = frame.images[reference_].type() == CV_32FC3
                            ? frame.images[reference_]
                            : ToFloatBgr(frame.images[reference_], "reference image");
  if (current && options_.align_to_current) {
    out.alignment = AlignSurfaceToModel(out.depth.depth, out.mask, camera, *current, cam_from_obj,
                                        options_.alignment);
    if (out.alignment.ok) {
      // The measured points p belong at correction * p: the object frame seen from the
      // camera is correction^-1 * cam_from_obj.
      cam_from_obj = out.alignment.cam_correction.Inverse() * cam_from_obj;
      out.world_from_obj = ref.world_from_cam * cam_from_obj;
    }
  }
  std::string why;
  out.mesh = BuildSurfaceMesh(out.depth, image, camera, cam_from_obj, out.mask, options_.mesh,
                              &out.report, &why);
  if (!out.mesh) out.why = why;
  out.mesh_ms = timer.ElapsedMilliseconds();
  return out;
}

std::optional<Rigid3d> Modeller::InitialPose(const Frame& frame, const PixelRect& region,
                                             const cv::Mat& mask, MaskRole mask_role) const {
  const RigCamera& ref = rig_.cameras[reference_];
  const PinholeCamera& camera = ref.intrinsics;
  const PixelRect r = region.Intersect(camera.ImageRect());
  if (r.empty()) return std::nullopt;
  const DepthMap map = (initial_pose_source_ ? *initial_pose_source_ : *source_).Extract(frame, r);
  std::vector<float> depths;
  for (int y = r.y0; y < r.y1; ++y) {
    for (int x = r.x0; x < r.x1; ++x) {
      if (!mask.empty() && !mask.at<uint8_t>(y, x)) continue;
      const float z = map.depth.at<float>(y, x);
      if (z > 0.0f) depths.push_back(z);
    }
  }
  if (depths.empty()) return std::nullopt;
  const double quantile = options_.depth.source == DepthSourceKind::kSensor && !mask.empty() &&
                                  mask_role == MaskRole::kSelects
                              ? options_.sensor_mask_depth_quantile
                              : 0.5;
  const auto at = depths.begin() + static_cast<std::ptrdiff_t>(quantile * (depths.size() - 1));
  std::nth_element(depths.begin(), at, depths.end());
  const double z = *at + options_.origin_offset_m;
  const Eigen::Vector2d centre(0.5 * (r.x0 + r.x1 - 1), 0.5 * (r.y0 + r.y1 - 1));
  const Rigid3d cam_from_obj(Eigen::Quaterniond::Identity(), camera.Unproject(centre, z));
  return ref.world_from_cam * cam_from_obj;
}

}  // namespace unseen
