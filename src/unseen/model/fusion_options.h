// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Options of incremental modelling: the object-frame volume (tsdf_volume.h) and the fused
// model made from it (model_fusion.h). Checked in modeller_options.cc with the modeller's
// other options; read from the `fusion` section of the modeller's YAML.
#pragma once

namespace unseen {

struct TsdfOptions {
  int voxels_per_side = 128;       // the grid's resolution along each axis
  double min_voxel_m = 0.002;      // the voxel's edge is never smaller (small objects)
  double truncation_voxels = 3.0;  // |signed distance| kept, in voxels (>= 1.5)
  float max_weight = 32.0f;        // cap on a voxel's summed weight: later maps still count
  // Pixels outside the object's mask whose depth lies behind a voxel say the voxel is free
  // space (the object's silhouette carves the volume); their weight relative to a surface
  // measurement. 0: only the object's pixels are fused.
  float free_space_weight = 0.5f;
  // Voxels this close to the support plane the segmentation found (or below it) are free
  // space: the table the object stands on never joins the model.
  double support_margin_m = 0.003;
  // Parts of the surface with fewer triangles than this share of the largest connected
  // part are dropped (specks of depth noise).
  double min_component_share = 0.05;
  void Check() const;
};

struct ModelFusionOptions {
  TsdfOptions volume;
  // The volume's half edge: this times the first model's farthest vertex from the object
  // frame's origin (capped by the modeller's segmentation radius), so the sides not yet
  // seen fit in.
  double extent_factor = 1.6;
  // A build's image becomes a key view (projector) when the direction from the object to
  // its camera is this far from every key view's; the first key view of a direction is
  // kept (a later one would paint the texture where a drifted pose puts it).
  double key_view_spacing_deg = 30.0;
  int max_key_views = 8;
  // The last build's image textures the model too, where it faces the surface best: what
  // the camera sees now was lit as it is now (a key view's shading was baked in under
  // another orientation towards the light). Off by default: its texture is painted where
  // that frame's tracked pose put it, so each build hands the tracker that frame's error
  // and the object frame drifts (5-camera cube: end rotation 1.77 -> 1.41 deg, mean 1.41 ->
  // 0.86 deg without it; better on 7 of 9 development and rendered RGB-D runs, equal on the
  // real cube, mixed on the 5-camera cube's stereo model).
  bool latest_view = false;
  // The surface handed to the tracker is decimated (mesh/decimate.h) to this many
  // triangles, moving it by at most max_error_voxels voxels.
  int max_triangles = 2000;
  double max_error_voxels = 0.5;
  // The fused surface must cover at least this share of what the build's own mesh covers in
  // the build's image (both rendered at the build's pose): sparse or far depth (a sensor's
  // holes, an object near its range) leaves the volume with a few scattered voxels whose
  // surface is no model, and the build's own mesh, which spans its holes, is kept instead.
  double min_coverage = 0.5;
  void Check() const;
};

}  // namespace unseen
