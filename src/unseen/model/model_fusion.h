// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Incremental modelling (SPEC 5.4, required beyond the thesis's periodic replacement):
// every build's depth map, seen at the tracked pose, is fused into one volume in the
// object frame (tsdf_volume.h), and the model handed to the tracker is the volume's
// surface textured by the key views' images (projective textures, SPEC 5.3). Unlike a
// rebuild, which makes the object frame wherever the tracked pose put it, the fused model
// keeps the frame the first build fixed — a new map's error is averaged with every earlier
// one instead of replacing them — and it grows to cover every side the cameras have seen.
//
// Why a volume rather than surfels: the tracker renders triangles, and a TSDF gives a
// closed, de-noised triangle surface with no extra meshing step; its memory is bounded by
// the object's size (128^3 voxels, 17 MB), and a depth map is fused in 28-63 ms on
// the modelling thread. Colour stays in the key views' images (sharper than per-voxel
// colour at the voxel size, and the tracker's photometric term wants the texture's detail).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "unseen/camera/camera.h"
#include "unseen/mesh/mesh.h"
#include "unseen/model/fusion_options.h"
#include "unseen/model/modeller.h"
#include "unseen/model/tsdf_volume.h"

namespace unseen {

struct FusionReport {
  int fused = 0;              // depth maps fused so far
  int key_views = 0;          // projectors of the model
  int surface_triangles = 0;  // of the last extracted surface, before decimation
  int triangles = 0;          // of the last model
  float voxel_mm = 0.0f;
  // Of the last model: what it covers in the build's image over what the build's mesh covers.
  double coverage = 0.0;
  TsdfIntegration last;  // of the last map
  double fuse_ms = 0.0;  // of the last map: integration, extraction and key views
};

class ModelFusion {
 public:
  // `reference`: the camera the builds' depth maps are in. `max_radius_m`: the largest
  // object (the modeller's segmentation radius). Throws unseen::Error for invalid options.
  ModelFusion(const RigCamera& reference, double max_radius_m, const ModelFusionOptions& options);

  // Folds in a successful build (its depth map, object mask, projector and object frame);
  // the first sizes the volume. Returns the fused model, or std::nullopt with `why` when
  // the volume holds no surface yet or one covering too little of the build's view
  // (ModelFusionOptions::min_coverage); the build is still fused.
  std::optional<Mesh> Fuse(const ModelBuild& build, std::string* why);

  const FusionReport& report() const { return report_; }
  // Null before the first build.
  const TsdfVolume* volume() const { return volume_ ? &*volume_ : nullptr; }

 private:
  RigCamera reference_;
  double max_radius_m_;
  ModelFusionOptions options_;
  std::optional<TsdfVolume> volume_;
  std::vector<Projector> key_views_;
  std::optional<Projector> latest_view_;  // the last build's, when not a key view
  FusionReport report_;
};

}  // namespace unseen
