// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// ModellerOptions from YAML: sections depth, plane_sweep, stereo, segmentation, mesh, model.
#include <map>
#include <string>

#include "unseen/model/modeller.h"
#include "unseen/util/error.h"
#include "unseen/util/yaml_options.h"

namespace unseen {
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
  const std::map<std::string, YamlSection> sections = {
      {"depth",
       {{"source", YamlEnumField(&d.source, &ParseSource)},
        {"min_depth_m", YamlField(&d.min_depth_m)},
        {"max_depth_m", YamlField(&d.max_depth_m)},
        {"min_texturedness", YamlField(&d.min_texturedness)}}},
      {"plane_sweep",
       {{"planes", YamlField(&ps.planes)},
        {"window_px", YamlField(&ps.window_px)},
        {"best_share", YamlField(&ps.best_share)},
        {"max_cost", YamlField(&ps.max_cost)},
        {"uniqueness", YamlField(&ps.uniqueness)},
        {"min_support", YamlField(&ps.min_support)},
        {"refine_iterations", YamlField(&ps.refine_iterations)},
        {"smoothness", YamlField(&ps.smoothness)}}},
      {"stereo",
       {{"num_disparities", YamlField(&st.num_disparities)},
        {"block_size", YamlField(&st.block_size)},
        {"uniqueness_ratio", YamlField(&st.uniqueness_ratio)},
        {"speckle_window", YamlField(&st.speckle_window)},
        {"speckle_range", YamlField(&st.speckle_range)},
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
        {"align_to_current", YamlField(&o.align_to_current)}}},
      {"alignment",
       {{"iterations", YamlField(&al.iterations)},
        {"max_distance_m", YamlField(&al.max_distance_m)},
        {"huber_m", YamlField(&al.huber_m)},
        {"min_points", YamlField(&al.min_points)},
        {"damping", YamlField(&al.damping)},
        {"max_correction_m", YamlField(&al.max_correction_m)},
        {"max_correction_deg", YamlField(&al.max_correction_deg)}}},
  };
  ApplyYamlSections(root, what, sections);
  try {
    o.Check();
  } catch (const Error& e) {
    ThrowError("{}: {}", what, e.what());
  }
  return o;
}

}  // namespace

ModellerOptions ParseModellerOptions(const std::string& yaml_text, const std::string& what) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    ThrowError("{}: malformed YAML: {}", what, e.what());
  }
  return FromYaml(root, what, ModellerOptions());
}

ModellerOptions LoadModellerOptions(const std::string& path, const ModellerOptions& defaults) {
  return FromYaml(LoadYamlFile(path, "modeller options"), path, defaults);
}

}  // namespace unseen
