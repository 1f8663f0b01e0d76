// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The on-line modeller (SPEC 5, thesis chapter 3): from one frame of the rig, an
// approximate textured model of the object of interest in a given object frame — depth
// map (depth_extraction.h), segmentation (object_segmentation.h), mesh and projective
// texture (surface_mesh.h) — for the tracker to track an object it has no model of. Also
// the initial object frame for a selected region (SPEC 4.4).
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/io/sequence.h"
#include "unseen/mesh/mesh.h"
#include "unseen/model/depth_extraction.h"
#include "unseen/model/fusion_options.h"
#include "unseen/model/object_segmentation.h"
#include "unseen/model/surface_alignment.h"
#include "unseen/model/surface_mesh.h"

namespace unseen {

struct ModellerOptions {
  DepthExtractionOptions depth;
  SegmentationOptions segmentation;
  SurfaceMeshOptions mesh;  // max_radius_m 0: segmentation.max_radius_m
  // SPEC 4.4: the origin of a new object frame lies this far behind the visible surface at
  // the region's centre (inside the object).
  double origin_offset_m = 0.02;
  // The visible surface there is the median of the depths measured in the region (inside
  // its mask); with a depth sensor and a mask of the pixels that moved (MaskRole::
  // kSelects), this quantile of theirs: an object moving before a textured background
  // moves the blocks along its outline on both sides, the background's may hold most of
  // them (held-out untextured teapot before a photo: 80 %; the first model was the
  // photo's), and the object is the nearer surface.
  double sensor_mask_depth_quantile = 0.1;
  // The plane sweep that places a new object frame searches the whole depth range
  // (depth.min_depth_m to max_depth_m) with at least this many planes: at the object's
  // range's 64 over 0.1-5 m, neighbouring planes of a wide rig (cameras 35 deg apart) are
  // pixels apart at the object and the match aliases (held-out three-camera teapot: its
  // origin placed 15 cm too near, 3 % tracked; at 256 planes 88 %).
  int initial_pose_planes = 256;
  // A rebuild's new surface is first aligned to the model in use (surface_alignment.h), so
  // that the object frame does not drift with the tracked pose's error. Off by default, by
  // measurement: the depth is less accurate than the tracked pose on the sequences at hand
  // (5-camera plane sweep at 1 m: ~1 cm per pixel of disparity, corrections of 10-14 mm,
  // success 95 -> 74-88 %; the real cube's sensor depth, offset from its colour by a few
  // mm: corrections of 5-7 mm, no gain).
  bool align_to_current = false;
  SurfaceAlignmentOptions alignment;
  ModelFusionOptions fusion;  // incremental model updates (model_updater.h)
  void Check() const;
};

// The options from YAML (sections depth, plane_sweep, stereo, segmentation, mesh, model,
// alignment, fusion;
// every key as the structs' fields), checked. Errors name the file (`what`), the section,
// the key and the value.
ModellerOptions ParseModellerOptions(const std::string& yaml_text, const std::string& what);
// The file's settings over `defaults`.
ModellerOptions LoadModellerOptions(const std::string& path,
                                    const ModellerOptions& defaults = ModellerOptions());

// One model build. `mesh` is empty when the frame could not be modelled (`why` says why:
// no depth, no texture, nothing left of the object); never an empty mesh.
struct ModelBuild {
  std::optional<Mesh> mesh;
  std::string why;
  DepthMap depth;              // the reference camera's depth map
  cv::Mat mask;                // the object's pixels used (CV_8UC1)
  PixelRect region;            // the region the depth was measured in
  Rigid3d world_from_obj;      // the object frame the model is in (corrected by `alignment`)
  SurfaceAlignment alignment;  // of the new surface to the model in use, for a rebuild
  SegmentationReport segmentation;
  SurfaceMeshReport report;
  double depth_ms = 0.0, mesh_ms = 0.0;
  bool ok() const { return mesh.has_value(); }
};

class Modeller {
 public:
  // At least this share of a given region must lie within the reference image: one mostly
  // beyond it is an object cut by the image border, whose border would be its outline.
  static constexpr double kMinRegionInside = 0.5;
  // The share of `region`'s area within `camera`'s image (0 for an empty region).
  static double ShareInside(const PixelRect& region, const PinholeCamera& camera) {
    return region.empty() ? 0.0
                          : double(region.Intersect(camera.ImageRect()).area()) / region.area();
  }

  // Throws unseen::Error for invalid options, a reference camera not in the rig, or a
  // depth source the rig cannot serve (DepthSource).
  Modeller(const Rig& rig, int reference, const ModellerOptions& options);

  // The model of the object seen from the reference camera in the frame `world_from_obj`.
  // `region`: where the object is in the reference image; empty: the rectangle of the
  // sphere of segmentation.max_radius_m about the origin. `mask` (optional, CV_8UC1 of the
  // reference camera's size): non-zero where the object may be (kBounds) or on pixels of
  // the object (kSelects: the pixels that moved with it; SegmentObject).
  // `current` (optional): the model in use, for a rebuild at the tracked `world_from_obj`;
  // with ModellerOptions::align_to_current the new surface is aligned to it first and the
  // model built in the corrected frame (ModelBuild::world_from_obj).
  ModelBuild Build(const Frame& frame, const Rigid3d& world_from_obj, const PixelRect& region,
                   const cv::Mat& mask = cv::Mat(), const Mesh* current = nullptr,
                   MaskRole mask_role = MaskRole::kBounds) const;

  // SPEC 4.4: the object frame for a region of the reference image: the centre of the
  // region back-projected to the median depth measured in it (inside `mask` if given; a
  // sensor's in a selecting mask: sensor_mask_depth_quantile), origin_offset_m deeper; axes the reference camera's. std::nullopt when nothing in the
  // region has depth.
  std::optional<Rigid3d> InitialPose(const Frame& frame, const PixelRect& region,
                                     const cv::Mat& mask = cv::Mat(),
                                     MaskRole mask_role = MaskRole::kBounds) const;

  const ModellerOptions& options() const { return options_; }
  int reference() const { return reference_; }
  const Rig& rig() const { return rig_; }

 private:
  Rig rig_;
  int reference_;
  ModellerOptions options_;
  std::unique_ptr<DepthSource> source_;
  // InitialPose's whole-range sweep, when it needs more planes than source_; else null.
  std::unique_ptr<DepthSource> initial_pose_source_;
};

}  // namespace unseen
