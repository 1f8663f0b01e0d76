// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The modeller's options: every options struct's Check (kept apart from the code that uses
// them, so that the YAML reader builds alone: fuzz/model_options_fuzzer.cc) and their
// reading from YAML (sections depth, plane_sweep, stereo, segmentation, mesh, model, fusion,
// alignment).
#include <cmath>
#include <map>
#include <string>

#include "unseen/model/modeller.h"
#include "unseen/util/error.h"
#include "unseen/util/yaml_options.h"

namespace unseen {

std::string ToString(DepthSourceKind kind) {
  switch (kind) {
    case DepthSourceKind::kPlaneSweep:
      return "planesweep";
    case DepthSourceKind::kStereo:
      return "stereo";
    case DepthSourceKind::kSensor:
      return "sensor";
  }
  return "?";
}

DepthSourceKind ParseDepthSourceKind(const std::string& text) {
  for (DepthSourceKind k :
       {DepthSourceKind::kPlaneSweep, DepthSourceKind::kStereo, DepthSourceKind::kSensor}) {
    if (text == ToString(k)) return k;
  }
  ThrowError("depth source '{}' is not one of planesweep, stereo, sensor", text);
}

void PlaneSweepOptions::Check() const {
  UNSEEN_CHECK(planes >= 4 && planes <= 1024, "plane_sweep.planes {} must be in [4, 1024]", planes);
  UNSEEN_CHECK(disparity_step_px >= 0.0 && disparity_step_px <= 16.0,
               "plane_sweep.disparity_step_px {} must be in [0, 16]", disparity_step_px);
  UNSEEN_CHECK(window_px >= 3 && window_px % 2 == 1 && window_px <= 31,
               "plane_sweep.window_px {} must be odd and in [3, 31]", window_px);
  UNSEEN_CHECK(best_share > 0.0 && best_share <= 1.0, "plane_sweep.best_share {} must be in (0, 1]",
               best_share);
  UNSEEN_CHECK(max_cost > 0.0 && max_cost <= 2.0, "plane_sweep.max_cost {} must be in (0, 2]",
               max_cost);
  UNSEEN_CHECK(uniqueness >= 0.0 && uniqueness < 1.0, "plane_sweep.uniqueness {} must be in [0, 1)",
               uniqueness);
  UNSEEN_CHECK(min_support >= 0 && min_support <= 24,
               "plane_sweep.min_support {} must be in [0, 24]", min_support);
  UNSEEN_CHECK(refine_iterations >= 0 && refine_iterations <= 10,
               "plane_sweep.refine_iterations {} must be in [0, 10]", refine_iterations);
  UNSEEN_CHECK(smoothness >= 0.0 && std::isfinite(smoothness),
               "plane_sweep.smoothness {} must be >= 0", smoothness);
  UNSEEN_CHECK(levels >= 1 && levels <= 5, "plane_sweep.levels {} must be in [1, 5]", levels);
  UNSEEN_CHECK(band_planes >= 1 && band_planes <= 64,
               "plane_sweep.band_planes {} must be in [1, 64]", band_planes);
  UNSEEN_CHECK(threads >= 0 && threads <= 256, "plane_sweep.threads {} must be in [0, 256]",
               threads);
}

void StereoOptions::Check() const {
  UNSEEN_CHECK(num_disparities >= 16 && num_disparities % 16 == 0 && num_disparities <= 512,
               "stereo.num_disparities {} must be a multiple of 16 in [16, 512]", num_disparities);
  UNSEEN_CHECK(block_size >= 3 && block_size % 2 == 1 && block_size <= 21,
               "stereo.block_size {} must be odd and in [3, 21]", block_size);
  UNSEEN_CHECK(uniqueness_ratio >= 0 && uniqueness_ratio <= 100,
               "stereo.uniqueness_ratio {} must be in [0, 100]", uniqueness_ratio);
  UNSEEN_CHECK(speckle_window >= 0, "stereo.speckle_window {} must be >= 0", speckle_window);
  UNSEEN_CHECK(speckle_range >= 1, "stereo.speckle_range {} must be >= 1", speckle_range);
}

void DepthExtractionOptions::Check() const {
  UNSEEN_CHECK(min_depth_m > 0.0 && std::isfinite(min_depth_m), "depth.min_depth_m {} must be > 0",
               min_depth_m);
  UNSEEN_CHECK(max_depth_m > min_depth_m && std::isfinite(max_depth_m),
               "depth.max_depth_m {} must be > min_depth_m {}", max_depth_m, min_depth_m);
  UNSEEN_CHECK(min_texturedness >= 0.0 && std::isfinite(min_texturedness),
               "depth.min_texturedness {} must be >= 0", min_texturedness);
  plane_sweep.Check();
  stereo.Check();
}

void SegmentationOptions::Check() const {
  UNSEEN_CHECK(max_radius_m > 0.0 && std::isfinite(max_radius_m),
               "segmentation.max_radius_m {} must be > 0", max_radius_m);
  UNSEEN_CHECK(plane_tolerance_m > 0.0 && std::isfinite(plane_tolerance_m),
               "segmentation.plane_tolerance_m {} must be > 0", plane_tolerance_m);
  UNSEEN_CHECK(plane_normal_deg > 0.0 && plane_normal_deg <= 90.0,
               "segmentation.plane_normal_deg {} must be in (0, 90]", plane_normal_deg);
  UNSEEN_CHECK(plane_iterations >= 1 && plane_iterations <= 100000,
               "segmentation.plane_iterations {} must be in [1, 100000]", plane_iterations);
  UNSEEN_CHECK(min_plane_share > 0.0 && min_plane_share <= 1.0,
               "segmentation.min_plane_share {} must be in (0, 1]", min_plane_share);
  UNSEEN_CHECK(max_depth_step > 0.0 && std::isfinite(max_depth_step),
               "segmentation.max_depth_step {} must be > 0", max_depth_step);
  UNSEEN_CHECK(sparse_gap_px >= 1 && sparse_gap_px <= 32,
               "segmentation.sparse_gap_px {} must be in [1, 32]", sparse_gap_px);
  UNSEEN_CHECK(sparse_fill_px >= 0 && sparse_fill_px <= 64,
               "segmentation.sparse_fill_px {} must be in [0, 64]", sparse_fill_px);
  UNSEEN_CHECK(dense_share >= 0.0 && dense_share <= 1.0,
               "segmentation.dense_share {} must be in [0, 1]", dense_share);
  UNSEEN_CHECK(min_component_share >= 0.0 && min_component_share <= 1.0,
               "segmentation.min_component_share {} must be in [0, 1]", min_component_share);
  UNSEEN_CHECK(min_connected_share >= 0.0 && min_connected_share <= 1.0,
               "segmentation.min_connected_share {} must be in [0, 1]", min_connected_share);
}

void SurfaceMeshOptions::Check() const {
  UNSEEN_CHECK(median_px == 1 || median_px == 3 || median_px == 5,
               "mesh.median_px {} must be 1, 3 or 5", median_px);
  UNSEEN_CHECK(cell_px >= 3 && cell_px <= 256, "mesh.cell_px {} must be in [3, 256]", cell_px);
  UNSEEN_CHECK(min_texturedness >= 0.0 && std::isfinite(min_texturedness),
               "mesh.min_texturedness {} must be >= 0", min_texturedness);
  UNSEEN_CHECK(harris_k > 0.0 && harris_k < 0.25, "mesh.harris_k {} must be in (0, 0.25)",
               harris_k);
  UNSEEN_CHECK(harris_quality > 0.0 && harris_quality <= 1.0,
               "mesh.harris_quality {} must be in (0, 1]", harris_quality);
  UNSEEN_CHECK(max_radius_m >= 0.0 && std::isfinite(max_radius_m),
               "mesh.max_radius_m {} must be >= 0", max_radius_m);
  UNSEEN_CHECK(max_depth_step > 0.0 && std::isfinite(max_depth_step),
               "mesh.max_depth_step {} must be > 0", max_depth_step);
  UNSEEN_CHECK(min_depth_step_m >= 0.0 && std::isfinite(min_depth_step_m),
               "mesh.min_depth_step_m {} must be >= 0", min_depth_step_m);
}

void SurfaceAlignmentOptions::Check() const {
  UNSEEN_CHECK(iterations >= 1 && iterations <= 100, "alignment.iterations {} must be in [1, 100]",
               iterations);
  UNSEEN_CHECK(max_distance_m > 0.0, "alignment.max_distance_m {} must be > 0", max_distance_m);
  UNSEEN_CHECK(huber_m > 0.0, "alignment.huber_m {} must be > 0", huber_m);
  UNSEEN_CHECK(min_points >= 6, "alignment.min_points {} must be >= 6", min_points);
  UNSEEN_CHECK(damping >= 0.0 && damping < 1.0, "alignment.damping {} must be in [0, 1)", damping);
  UNSEEN_CHECK(max_correction_m > 0.0 && max_correction_deg > 0.0,
               "alignment.max_correction_m {} and max_correction_deg {} must be > 0",
               max_correction_m, max_correction_deg);
}

void TsdfOptions::Check() const {
  UNSEEN_CHECK(voxels_per_side >= 8 && voxels_per_side <= 512,
               "fusion.voxels_per_side {} must be in [8, 512]", voxels_per_side);
  UNSEEN_CHECK(min_voxel_m > 0.0 && std::isfinite(min_voxel_m), "fusion.min_voxel_m {} must be > 0",
               min_voxel_m);
  UNSEEN_CHECK(truncation_voxels >= 1.5 && truncation_voxels <= 50.0,
               "fusion.truncation_voxels {} must be in [1.5, 50]", truncation_voxels);
  UNSEEN_CHECK(max_weight >= 1.0f && std::isfinite(max_weight), "fusion.max_weight {} must be >= 1",
               max_weight);
  UNSEEN_CHECK(free_space_weight >= 0.0f && free_space_weight <= 1.0f,
               "fusion.free_space_weight {} must be in [0, 1]", free_space_weight);
  UNSEEN_CHECK(support_margin_m >= 0.0 && std::isfinite(support_margin_m),
               "fusion.support_margin_m {} must be >= 0", support_margin_m);
  UNSEEN_CHECK(min_component_share >= 0.0 && min_component_share <= 1.0,
               "fusion.min_component_share {} must be in [0, 1]", min_component_share);
}

void ModelFusionOptions::Check() const {
  volume.Check();
  UNSEEN_CHECK(extent_factor >= 1.0 && extent_factor <= 10.0,
               "fusion.extent_factor {} must be in [1, 10]", extent_factor);
  UNSEEN_CHECK(key_view_spacing_deg >= 0.0 && key_view_spacing_deg <= 180.0,
               "fusion.key_view_spacing_deg {} must be in [0, 180]", key_view_spacing_deg);
  UNSEEN_CHECK(max_key_views >= 1 && max_key_views <= 64,
               "fusion.max_key_views {} must be in [1, 64]", max_key_views);
  UNSEEN_CHECK(max_triangles >= 4, "fusion.max_triangles {} must be >= 4", max_triangles);
  UNSEEN_CHECK(max_error_voxels >= 0.0 && max_error_voxels <= 10.0,
               "fusion.max_error_voxels {} must be in [0, 10]", max_error_voxels);
  UNSEEN_CHECK(min_coverage >= 0.0 && min_coverage <= 1.0,
               "fusion.min_coverage {} must be in [0, 1]", min_coverage);
}

void ModellerOptions::Check() const {
  depth.Check();
  segmentation.Check();
  mesh.Check();
  alignment.Check();
  fusion.Check();
  UNSEEN_CHECK(origin_offset_m >= 0.0 && std::isfinite(origin_offset_m),
               "model.origin_offset_m {} must be >= 0", origin_offset_m);
  UNSEEN_CHECK(sensor_mask_depth_quantile >= 0.0 && sensor_mask_depth_quantile <= 1.0,
               "model.sensor_mask_depth_quantile {} must be in [0, 1]", sensor_mask_depth_quantile);
  UNSEEN_CHECK(initial_pose_planes >= 4 && initial_pose_planes <= 1024,
               "model.initial_pose_planes {} must be in [4, 1024]", initial_pose_planes);
}

namespace {

DepthSourceKind ParseSource(const std::string& text, const std::string& where) {
  try {
    return ParseDepthSourceKind(text);
  } catch (const Error& e) {
    ThrowError("{}: {}", where, e.what());
  }
}

ModellerOptions FromYaml(const YAML::Node& root, const std::string& what, ModellerOptions o) {
  DepthExtractionOptions& d = o.depth;
  PlaneSweepOptions& ps = d.plane_sweep;
  StereoOptions& st = d.stereo;
  SegmentationOptions& sg = o.segmentation;
  SurfaceMeshOptions& me = o.mesh;
  SurfaceAlignmentOptions& al = o.alignment;
  ModelFusionOptions& fu = o.fusion;
  const std::map<std::string, YamlSection> sections = {
      {"depth",
       {{"source", YamlEnumField(&d.source, &ParseSource)},
        {"min_depth_m", YamlField(&d.min_depth_m)},
        {"max_depth_m", YamlField(&d.max_depth_m)},
        {"min_texturedness", YamlField(&d.min_texturedness)}}},
      {"plane_sweep",
       {{"planes", YamlField(&ps.planes)},
        {"disparity_step_px", YamlField(&ps.disparity_step_px)},
        {"window_px", YamlField(&ps.window_px)},
        {"best_share", YamlField(&ps.best_share)},
        {"max_cost", YamlField(&ps.max_cost)},
        {"uniqueness", YamlField(&ps.uniqueness)},
        {"min_support", YamlField(&ps.min_support)},
        {"refine_iterations", YamlField(&ps.refine_iterations)},
        {"smoothness", YamlField(&ps.smoothness)},
        {"levels", YamlField(&ps.levels)},
        {"band_planes", YamlField(&ps.band_planes)},
        {"search_behind", YamlField(&ps.search_behind)},
        {"threads", YamlField(&ps.threads)}}},
      {"stereo",
       {{"num_disparities", YamlField(&st.num_disparities)},
        {"block_size", YamlField(&st.block_size)},
        {"uniqueness_ratio", YamlField(&st.uniqueness_ratio)},
        {"speckle_window", YamlField(&st.speckle_window)},
        {"speckle_range", YamlField(&st.speckle_range)},
        {"search_behind", YamlField(&st.search_behind)},
        {"other_camera", YamlField(&st.other_camera)}}},
      {"segmentation",
       {{"max_radius_m", YamlField(&sg.max_radius_m)},
        {"remove_support_plane", YamlField(&sg.remove_support_plane)},
        {"plane_tolerance_m", YamlField(&sg.plane_tolerance_m)},
        {"plane_normal_deg", YamlField(&sg.plane_normal_deg)},
        {"plane_iterations", YamlField(&sg.plane_iterations)},
        {"min_plane_share", YamlField(&sg.min_plane_share)},
        {"max_depth_step", YamlField(&sg.max_depth_step)},
        {"dense_share", YamlField(&sg.dense_share)},
        {"min_component_share", YamlField(&sg.min_component_share)},
        {"min_connected_share", YamlField(&sg.min_connected_share)},
        {"sparse_gap_px", YamlField(&sg.sparse_gap_px)},
        {"sparse_fill_px", YamlField(&sg.sparse_fill_px)}}},
      {"mesh",
       {{"median_px", YamlField(&me.median_px)},
        {"cell_px", YamlField(&me.cell_px)},
        {"min_texturedness", YamlField(&me.min_texturedness)},
        {"harris_k", YamlField(&me.harris_k)},
        {"harris_quality", YamlField(&me.harris_quality)},
        {"untextured_vertices", YamlField(&me.untextured_vertices)},
        {"contour_vertices", YamlField(&me.contour_vertices)},
        {"max_radius_m", YamlField(&me.max_radius_m)},
        {"max_depth_step", YamlField(&me.max_depth_step)},
        {"min_depth_step_m", YamlField(&me.min_depth_step_m)}}},
      {"model",
       {{"origin_offset_m", YamlField(&o.origin_offset_m)},
        {"sensor_mask_depth_quantile", YamlField(&o.sensor_mask_depth_quantile)},
        {"initial_pose_planes", YamlField(&o.initial_pose_planes)},
        {"align_to_current", YamlField(&o.align_to_current)}}},
      {"alignment",
       {{"iterations", YamlField(&al.iterations)},
        {"max_distance_m", YamlField(&al.max_distance_m)},
        {"huber_m", YamlField(&al.huber_m)},
        {"min_points", YamlField(&al.min_points)},
        {"damping", YamlField(&al.damping)},
        {"max_correction_m", YamlField(&al.max_correction_m)},
        {"max_correction_deg", YamlField(&al.max_correction_deg)}}},
      {"fusion",
       {{"voxels_per_side", YamlField(&fu.volume.voxels_per_side)},
        {"min_voxel_m", YamlField(&fu.volume.min_voxel_m)},
        {"truncation_voxels", YamlField(&fu.volume.truncation_voxels)},
        {"max_weight", YamlField(&fu.volume.max_weight)},
        {"free_space_weight", YamlField(&fu.volume.free_space_weight)},
        {"support_margin_m", YamlField(&fu.volume.support_margin_m)},
        {"min_component_share", YamlField(&fu.volume.min_component_share)},
        {"extent_factor", YamlField(&fu.extent_factor)},
        {"key_view_spacing_deg", YamlField(&fu.key_view_spacing_deg)},
        {"max_key_views", YamlField(&fu.max_key_views)},
        {"latest_view", YamlField(&fu.latest_view)},
        {"min_coverage", YamlField(&fu.min_coverage)},
        {"max_triangles", YamlField(&fu.max_triangles)},
        {"max_error_voxels", YamlField(&fu.max_error_voxels)}}},
  };
  ApplyYamlSections(root, what, sections);
  CheckOptionsFrom(o, what);
  return o;
}

}  // namespace

ModellerOptions ParseModellerOptions(const std::string& yaml_text, const std::string& what) {
  const YAML::Node root = ParseYamlText(yaml_text, what);
  return FromYaml(root, what, ModellerOptions());
}

ModellerOptions LoadModellerOptions(const std::string& path, const ModellerOptions& defaults) {
  return FromYaml(LoadYamlFile(path, "modeller options"), path, defaults);
}

}  // namespace unseen
