// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/tracker_options.h"

#include <cmath>
#include <functional>
#include <map>

#include <yaml-cpp/yaml.h>

#include "unseen/util/error.h"

namespace unseen {

void PyramidOptions::Check() const {
  UNSEEN_CHECK(max_levels >= 1 && max_levels <= 8, "pyramid.max_levels {} must be in [1, 8]",
               max_levels);
  UNSEEN_CHECK(min_object_px >= 4.0 && std::isfinite(min_object_px),
               "pyramid.min_object_px {} must be >= 4", min_object_px);
  UNSEEN_CHECK(max_iterations_per_level >= 1 && max_iterations_per_level <= 100,
               "pyramid.max_iterations_per_level {} must be in [1, 100]",
               max_iterations_per_level);
  UNSEEN_CHECK(min_update_px >= 0.0 && std::isfinite(min_update_px),
               "pyramid.min_update_px {} must be >= 0", min_update_px);
  UNSEEN_CHECK(coarse_max_iterations >= 1 && coarse_max_iterations <= 100,
               "pyramid.coarse_max_iterations {} must be in [1, 100]", coarse_max_iterations);
  UNSEEN_CHECK(coarse_min_update_px >= 0.0 && std::isfinite(coarse_min_update_px),
               "pyramid.coarse_min_update_px {} must be >= 0", coarse_min_update_px);
  UNSEEN_CHECK(max_step_px > 0.0 && std::isfinite(max_step_px),
               "pyramid.max_step_px {} must be > 0", max_step_px);
  UNSEEN_CHECK(resample_iterations >= 0 && resample_iterations <= 100,
               "pyramid.resample_iterations {} must be in [0, 100]", resample_iterations);
  UNSEEN_CHECK(resample_margin_px >= 0 && resample_margin_px <= 64,
               "pyramid.resample_margin_px {} must be in [0, 64]", resample_margin_px);
  UNSEEN_CHECK(rerender_px >= 0.0 && std::isfinite(rerender_px),
               "pyramid.rerender_px {} must be >= 0", rerender_px);
  UNSEEN_CHECK(rim_px >= 0 && rim_px <= 20, "pyramid.rim_px {} must be in [0, 20]", rim_px);
  UNSEEN_CHECK(min_adaptive_levels >= 1 && min_adaptive_levels <= max_levels,
               "pyramid.min_adaptive_levels {} must be in [1, max_levels = {}]",
               min_adaptive_levels, max_levels);
  UNSEEN_CHECK(capture_px > 0.0 && std::isfinite(capture_px),
               "pyramid.capture_px {} must be > 0", capture_px);
  UNSEEN_CHECK(prediction_margin >= 1.0 && std::isfinite(prediction_margin),
               "pyramid.prediction_margin {} must be >= 1", prediction_margin);
  UNSEEN_CHECK(correction_decay >= 0.0 && correction_decay < 1.0,
               "pyramid.correction_decay {} must be in [0, 1)", correction_decay);
  UNSEEN_CHECK(supersampled_levels >= 0 && supersampled_levels <= 8,
               "pyramid.supersampled_levels {} must be in [0, 8]", supersampled_levels);
}

void FailureOptions::Check() const {
  UNSEEN_CHECK(min_share >= 0.0 && good_share > min_share && good_share <= 1.0,
               "failure: need 0 <= min_share ({}) < good_share ({}) <= 1", min_share, good_share);
  UNSEEN_CHECK(good_region_residual_ratio >= 1.0 &&
                   bad_region_residual_ratio > good_region_residual_ratio &&
                   std::isfinite(bad_region_residual_ratio),
               "failure: need 1 <= good_region_residual_ratio ({}) < bad_region_residual_ratio "
               "({})", good_region_residual_ratio, bad_region_residual_ratio);
  UNSEEN_CHECK(min_reference_region_residual >= 0.0 && std::isfinite(min_reference_region_residual),
               "failure.min_reference_region_residual {} must be >= 0",
               min_reference_region_residual);
  UNSEEN_CHECK(min_used_px >= 0.0 && good_used_px > min_used_px,
               "failure: need 0 <= min_used_px ({}) < good_used_px ({})", min_used_px,
               good_used_px);
  UNSEEN_CHECK(good_residual_ratio >= 1.0 && bad_residual_ratio > good_residual_ratio,
               "failure: need 1 <= good_residual_ratio ({}) < bad_residual_ratio ({})",
               good_residual_ratio, bad_residual_ratio);
  UNSEEN_CHECK(residual_reference_rate > 0.0 && residual_reference_rate <= 1.0,
               "failure.residual_reference_rate {} must be in (0, 1]", residual_reference_rate);
  UNSEEN_CHECK(min_reference_residual_px > 0.0 && std::isfinite(min_reference_residual_px),
               "failure.min_reference_residual_px {} must be > 0", min_reference_residual_px);
  UNSEEN_CHECK(good_residual_px >= 0.0 && bad_residual_px > good_residual_px,
               "failure: need 0 <= good_residual_px ({}) < bad_residual_px ({})",
               good_residual_px, bad_residual_px);
  UNSEEN_CHECK(good_update_px >= 0.0 && bad_update_px > good_update_px,
               "failure: need 0 <= good_update_px ({}) < bad_update_px ({})", good_update_px,
               bad_update_px);
  UNSEEN_CHECK(min_pixels >= 6, "failure.min_pixels {} must be >= 6", min_pixels);
  UNSEEN_CHECK(min_region_lines >= 1, "failure.min_region_lines {} must be >= 1",
               min_region_lines);
  UNSEEN_CHECK(0.0 <= min_area_ratio && min_area_ratio < good_area_ratio && good_area_ratio <= 1.0,
               "failure: need 0 <= min_area_ratio ({}) < good_area_ratio ({}) <= 1",
               min_area_ratio, good_area_ratio);
  UNSEEN_CHECK(area_memory_frames >= 0, "failure.area_memory_frames {} must be >= 0",
               area_memory_frames);
  UNSEEN_CHECK(lost_confidence >= 0.0 && lost_confidence <= 1.0,
               "failure.lost_confidence {} must be in [0, 1]", lost_confidence);
  UNSEEN_CHECK(recover_confidence >= lost_confidence && recover_confidence <= 1.0,
               "failure.recover_confidence {} must be in [lost_confidence = {}, 1]",
               recover_confidence, lost_confidence);
  UNSEEN_CHECK(lost_after_frames >= 1, "failure.lost_after_frames {} must be >= 1",
               lost_after_frames);
  UNSEEN_CHECK(coast_frames >= 0 && coast_frames <= 1000,
               "failure.coast_frames {} must be in [0, 1000]", coast_frames);
  UNSEEN_CHECK(search_offset > 0.0 && search_offset <= 10.0,
               "failure.search_offset {} must be in (0, 10]", search_offset);
}

void ReacquisitionOptions::Check() const {
  UNSEEN_CHECK(seed_object_px >= 8.0 && std::isfinite(seed_object_px),
               "reacquisition.seed_object_px {} must be >= 8", seed_object_px);
  UNSEEN_CHECK(search_radii > 0.0 && search_radii <= 20.0,
               "reacquisition.search_radii {} must be in (0, 20]", search_radii);
  UNSEEN_CHECK(min_correlation >= -1.0 && min_correlation <= 1.0,
               "reacquisition.min_correlation {} must be in [-1, 1]", min_correlation);
  UNSEEN_CHECK(max_seeds >= 1 && max_seeds <= 8, "reacquisition.max_seeds {} must be in [1, 8]",
               max_seeds);
  UNSEEN_CHECK(rotation_deg >= 0.0 && rotation_deg <= 90.0,
               "reacquisition.rotation_deg {} must be in [0, 90]", rotation_deg);
  UNSEEN_CHECK(max_candidates >= 0 && max_candidates <= 100,
               "reacquisition.max_candidates {} must be in [0, 100]", max_candidates);
  UNSEEN_CHECK(score_iterations >= 1 && score_iterations <= 100,
               "reacquisition.score_iterations {} must be in [1, 100]", score_iterations);
  UNSEEN_CHECK(score_levels >= 1 && score_levels <= 8,
               "reacquisition.score_levels {} must be in [1, 8]", score_levels);
  UNSEEN_CHECK(refine_candidates >= 0 && refine_candidates <= 100,
               "reacquisition.refine_candidates {} must be in [0, 100]", refine_candidates);
  UNSEEN_CHECK(min_score >= 0.0 && min_score <= 1.0,
               "reacquisition.min_score {} must be in [0, 1]", min_score);
  UNSEEN_CHECK(doubtful_confidence >= 0.0 && doubtful_confidence <= 1.0,
               "reacquisition.doubtful_confidence {} must be in [0, 1]", doubtful_confidence);
  UNSEEN_CHECK(min_seed_shift_px >= 0.0 && std::isfinite(min_seed_shift_px),
               "reacquisition.min_seed_shift_px {} must be >= 0", min_seed_shift_px);
}

void TrackerOptions::Check() const {
  preprocess.Check();
  selection.Check();
  solver.Check();
  pyramid.Check();
  predictor.Check();
  failure.Check();
  photometric.Check();
  depth.Check();
  region.Check();
  live_appearance.Check();
  simplify.Check();
  reacquisition.Check();
  UNSEEN_CHECK(frame_interval_s > 0.0 && std::isfinite(frame_interval_s),
               "frame_interval_s {} must be > 0", frame_interval_s);
  UNSEEN_CHECK(threads >= 0 && threads <= 256, "threads {} must be in [0, 256]", threads);
}

void PhotometricOptions::Check() const {
  UNSEEN_CHECK(weight > 0.0 && std::isfinite(weight), "photometric.weight {} must be > 0", weight);
  UNSEEN_CHECK(min_start_fit >= 0.0 && min_start_fit <= 1.0,
               "photometric.min_start_fit {} must be in [0, 1]", min_start_fit);
  UNSEEN_CHECK(start_drag_px >= 0.0 && std::isfinite(start_drag_px),
               "photometric.start_drag_px {} must be >= 0", start_drag_px);
  UNSEEN_CHECK(start_drag_ratio >= 1.0 && std::isfinite(start_drag_ratio),
               "photometric.start_drag_ratio {} must be >= 1", start_drag_ratio);
  UNSEEN_CHECK(dragged_weight >= 0.0 && dragged_weight <= 1.0,
               "photometric.dragged_weight {} must be in [0, 1]", dragged_weight);
  UNSEEN_CHECK(light_change_fit >= 0.0 && light_change_fit <= 1.0,
               "photometric.light_change_fit {} must be in [0, 1]", light_change_fit);
  UNSEEN_CHECK(light_change_max_gathering >= 0.0 && light_change_max_gathering <= 1.0,
               "photometric.light_change_max_gathering {} must be in [0, 1]",
               light_change_max_gathering);
}

namespace {

using Setter = std::function<void(const YAML::Node&, const std::string&)>;

template <typename T>
Setter Field(T* field) {
  return [field](const YAML::Node& node, const std::string& where) {
    try {
      *field = node.as<T>();
    } catch (const YAML::Exception&) {
      ThrowError("{}: value '{}' has the wrong type", where, YAML::Dump(node));
    }
  };
}

template <typename E>
Setter EnumField(E* field, E (*parse)(const std::string&, const std::string&)) {
  return [field, parse](const YAML::Node& node, const std::string& where) {
    std::string text;
    try {
      text = node.as<std::string>();
    } catch (const YAML::Exception&) {
      ThrowError("{}: value '{}' is not a string", where, YAML::Dump(node));
    }
    *field = parse(text, where);
  };
}

// A map key as text. Throws naming `where` for a key that is not a plain name (YAML allows
// lists and maps as keys: "? [a, b]: 1").
std::string KeyName(const YAML::Node& key, const std::string& where) {
  UNSEEN_CHECK(key.IsScalar(), "{}: key '{}' is not a plain name", where, YAML::Dump(key));
  return key.Scalar();
}

void ApplySection(const YAML::Node& node, const std::string& where,
                  const std::map<std::string, Setter>& fields) {
  UNSEEN_CHECK(node.IsMap(), "{}: expected a map of settings", where);
  for (const auto& kv : node) {
    const std::string key = KeyName(kv.first, where);
    const auto it = fields.find(key);
    if (it == fields.end()) {
      std::string known;
      for (const auto& f : fields) known += (known.empty() ? "" : ", ") + f.first;
      ThrowError("{}: unknown key '{}' (known: {})", where, key, known);
    }
    it->second(kv.second, where + "." + key);
  }
}

void Apply(const YAML::Node& root, const std::string& what, TrackerOptions* o) {
  if (root.IsNull()) return;
  PreprocessOptions& pp = o->preprocess;
  PixelSelectionOptions& se = o->selection;
  FlowSolverOptions& so = o->solver;
  PyramidOptions& py = o->pyramid;
  MotionPredictorOptions& pr = o->predictor;
  FailureOptions& fa = o->failure;
  ReacquisitionOptions& re = o->reacquisition;
  DepthModalityOptions& de = o->depth;
  RegionModalityOptions& rg = o->region;
  PhotometricOptions& ph = o->photometric;
  LiveAppearanceOptions& la = o->live_appearance;
  SimplifyOptions& si = o->simplify;
  const std::map<std::string, std::map<std::string, Setter>> sections = {
      {"photometric",
       {{"enabled", Field(&ph.enabled)},
        {"require_appearance", Field(&ph.require_appearance)},
        {"min_start_fit", Field(&ph.min_start_fit)},
        {"start_drag_px", Field(&ph.start_drag_px)},
        {"start_drag_ratio", Field(&ph.start_drag_ratio)},
        {"dragged_weight", Field(&ph.dragged_weight)},
        {"light_change_fit", Field(&ph.light_change_fit)},
        {"light_change_max_gathering", Field(&ph.light_change_max_gathering)},
        {"weight", Field(&ph.weight)}}},
      {"preprocess",
       {{"use_linf", Field(&pp.use_linf)},
        {"linf_sigma_px", Field(&pp.linf_sigma_px)},
        {"min_linf_sigma_px", Field(&pp.min_linf_sigma_px)},
        {"linf_epsilon", Field(&pp.linf_epsilon)},
        {"blur_sigma_px", Field(&pp.blur_sigma_px)},
        {"shading_transfer", Field(&pp.shading_transfer)},
        {"shading_sigma_px", Field(&pp.shading_sigma_px)},
        {"silhouette_gamma", Field(&pp.silhouette_gamma)}}},
      {"selection",
       {{"color_mode", EnumField(&se.color_mode, &ParseColorMode)},
        {"use_gradient_threshold", Field(&se.use_gradient_threshold)},
        {"min_gradient_sq", Field(&se.min_gradient_sq)},
        {"use_normal_flow_bound", Field(&se.use_normal_flow_bound)},
        {"max_normal_flow_px", Field(&se.max_normal_flow_px)},
        {"use_occlusion_rejection", Field(&se.use_occlusion_rejection)},
        {"occlusion_min_gradient_sq", Field(&se.occlusion_min_gradient_sq)},
        {"occlusion_max_angle_rad", Field(&se.occlusion_max_angle_rad)},
        {"occlusion_max_magnitude_diff", Field(&se.occlusion_max_magnitude_diff)},
        {"min_eigen_ratio", Field(&se.min_eigen_ratio)},
        {"block_px", Field(&se.block_px)},
        {"block_min_gradient", Field(&se.block_min_gradient)},
        {"block_min_share_ratio", Field(&se.block_min_share_ratio)},
        {"block_min_blocks", Field(&se.block_min_blocks)}}},
      {"solver",
       {{"kernel", EnumField(&so.kernel, &ParseRobustKernel)},
        {"kernel_width", Field(&so.kernel_width)},
        {"irls_iterations", Field(&so.irls_iterations)},
        {"min_scale_px", Field(&so.min_scale_px)},
        {"min_equations", Field(&so.min_equations)},
        {"damping", Field(&so.damping)}}},
      {"pyramid",
       {{"max_levels", Field(&py.max_levels)},
        {"min_object_px", Field(&py.min_object_px)},
        {"max_iterations_per_level", Field(&py.max_iterations_per_level)},
        {"min_update_px", Field(&py.min_update_px)},
        {"coarse_max_iterations", Field(&py.coarse_max_iterations)},
        {"coarse_min_update_px", Field(&py.coarse_min_update_px)},
        {"max_step_px", Field(&py.max_step_px)},
        {"resample_iterations", Field(&py.resample_iterations)},
        {"rerender_px", Field(&py.rerender_px)},
        {"resample_margin_px", Field(&py.resample_margin_px)},
        {"rim_px", Field(&py.rim_px)},
        {"supersampled_levels", Field(&py.supersampled_levels)},
        {"adaptive_levels", Field(&py.adaptive_levels)},
        {"min_adaptive_levels", Field(&py.min_adaptive_levels)},
        {"capture_px", Field(&py.capture_px)},
        {"prediction_margin", Field(&py.prediction_margin)},
        {"correction_decay", Field(&py.correction_decay)}}},
      {"predictor",
       {{"type", EnumField(&pr.type, &ParsePredictorType)},
        {"linear_accel_sigma", Field(&pr.linear_accel_sigma)},
        {"angular_accel_sigma", Field(&pr.angular_accel_sigma)},
        {"position_sigma", Field(&pr.position_sigma)},
        {"rotation_sigma", Field(&pr.rotation_sigma)},
        {"min_confidence", Field(&pr.min_confidence)},
        {"confidence_power", Field(&pr.confidence_power)}}},
      {"failure",
       {{"min_share", Field(&fa.min_share)},
        {"good_share", Field(&fa.good_share)},
        {"min_used_px", Field(&fa.min_used_px)},
        {"good_used_px", Field(&fa.good_used_px)},
        {"good_residual_px", Field(&fa.good_residual_px)},
        {"good_residual_ratio", Field(&fa.good_residual_ratio)},
        {"bad_residual_ratio", Field(&fa.bad_residual_ratio)},
        {"residual_reference_rate", Field(&fa.residual_reference_rate)},
        {"min_reference_residual_px", Field(&fa.min_reference_residual_px)},
        {"bad_residual_px", Field(&fa.bad_residual_px)},
        {"good_update_px", Field(&fa.good_update_px)},
        {"bad_update_px", Field(&fa.bad_update_px)},
        {"min_pixels", Field(&fa.min_pixels)},
        {"good_region_residual_ratio", Field(&fa.good_region_residual_ratio)},
        {"bad_region_residual_ratio", Field(&fa.bad_region_residual_ratio)},
        {"min_reference_region_residual", Field(&fa.min_reference_region_residual)},
        {"min_region_lines", Field(&fa.min_region_lines)},
        {"min_area_ratio", Field(&fa.min_area_ratio)},
        {"good_area_ratio", Field(&fa.good_area_ratio)},
        {"area_memory_frames", Field(&fa.area_memory_frames)},
        {"lost_confidence", Field(&fa.lost_confidence)},
        {"lost_after_frames", Field(&fa.lost_after_frames)},
        {"recover_confidence", Field(&fa.recover_confidence)},
        {"search_when_lost", Field(&fa.search_when_lost)},
        {"coast_frames", Field(&fa.coast_frames)},
        {"search_offset", Field(&fa.search_offset)}}},
      {"reacquisition",
       {{"use_correlation", Field(&re.use_correlation)},
        {"seed_object_px", Field(&re.seed_object_px)},
        {"search_radii", Field(&re.search_radii)},
        {"min_correlation", Field(&re.min_correlation)},
        {"max_seeds", Field(&re.max_seeds)},
        {"rotation_deg", Field(&re.rotation_deg)},
        {"max_candidates", Field(&re.max_candidates)},
        {"score_iterations", Field(&re.score_iterations)},
        {"score_levels", Field(&re.score_levels)},
        {"refine_candidates", Field(&re.refine_candidates)},
        {"min_score", Field(&re.min_score)},
        {"seed_when_doubtful", Field(&re.seed_when_doubtful)},
        {"doubtful_confidence", Field(&re.doubtful_confidence)},
        {"min_seed_shift_px", Field(&re.min_seed_shift_px)}}},
      {"depth",
       {{"enabled", Field(&de.enabled)},
        {"max_points", Field(&de.max_points)},
        {"max_distance_m", Field(&de.max_distance_m)},
        {"kernel", EnumField(&de.residual.kernel, &ParseRobustKernel)},
        {"kernel_width", Field(&de.residual.kernel_width)},
        {"min_scale_m", Field(&de.residual.min_scale)},
        {"min_noise_m", Field(&de.residual.min_noise)},
        {"max_noise_m", Field(&de.residual.max_noise)},
        {"damping", Field(&de.residual.damping)},
        {"weight", Field(&de.residual.weight)},
        {"agree_distance_m", Field(&de.agree_distance_m)},
        {"bad_agreement", Field(&de.bad_agreement)},
        {"good_agreement", Field(&de.good_agreement)},
        {"min_measured", Field(&de.min_measured)},
        {"max_hidden_share", Field(&de.max_hidden_share)}}},
      {"region",
       {{"enabled", Field(&rg.enabled)},
        {"bins_per_channel", Field(&rg.bins_per_channel)},
        {"max_lines", Field(&rg.max_lines)},
        {"line_px", Field(&rg.line_px)},
        {"learn_margin_px", Field(&rg.learn_margin_px)},
        {"learn_rate", Field(&rg.learn_rate)},
        {"min_sigma_px", Field(&rg.min_sigma_px)},
        {"max_sigma_px", Field(&rg.max_sigma_px)},
        {"min_contrast", Field(&rg.min_contrast)},
        {"kernel", EnumField(&rg.residual.kernel, &ParseRobustKernel)},
        {"kernel_width", Field(&rg.residual.kernel_width)},
        {"min_scale", Field(&rg.residual.min_scale)},
        {"min_noise", Field(&rg.residual.min_noise)},
        {"max_noise", Field(&rg.residual.max_noise)},
        {"damping", Field(&rg.residual.damping)},
        {"weight", Field(&rg.residual.weight)},
        {"bad_agreement", Field(&rg.bad_agreement)},
        {"good_agreement", Field(&rg.good_agreement)},
        {"min_start_edge_share", Field(&rg.min_start_edge_share)}}},
      {"live_appearance",
       {{"enabled", Field(&la.enabled)},
        {"always", Field(&la.always)},
        {"min_confidence", Field(&la.min_confidence)},
        {"refresh_frames", Field(&la.refresh_frames)},
        {"margin_px", Field(&la.margin_px)},
        {"occlusion_tolerance", Field(&la.occlusion_tolerance)},
        {"photometric_weight", Field(&la.photometric_weight)},
        {"poor_fit_share", Field(&la.poor_fit_share)},
        {"poor_fit_frames", Field(&la.poor_fit_frames)},
        {"poor_fit_best_share", Field(&la.poor_fit_best_share)},
        {"poor_fit_confidence", Field(&la.poor_fit_confidence)}}},
      {"simplify",
       {{"enabled", Field(&si.enabled)},
        {"max_normal_angle_rad", Field(&si.max_normal_angle_rad)},
        {"relative_tolerance", Field(&si.relative_tolerance)},
        {"attribute_tolerance", Field(&si.attribute_tolerance)},
        {"texture_shift_tolerance", Field(&si.texture_shift_tolerance)}}},
  };
  UNSEEN_CHECK(root.IsMap(), "{}: expected a map at the top level", what);
  for (const auto& kv : root) {
    const std::string key = KeyName(kv.first, what);
    if (key == "frame_interval_s") {
      Field(&o->frame_interval_s)(kv.second, what + ": " + key);
      continue;
    }
    if (key == "threads") {
      Field(&o->threads)(kv.second, what + ": " + key);
      continue;
    }
    const auto it = sections.find(key);
    if (it == sections.end()) {
      ThrowError("{}: unknown section '{}' (known: photometric, preprocess, selection, solver, "
                 "pyramid, "
                 "predictor, failure, reacquisition, depth, region, live_appearance, "
                 "frame_interval_s, threads)",
                 what, key);
    }
    ApplySection(kv.second, what + ": " + key, it->second);
  }
}

}  // namespace

TrackerOptions ParseTrackerOptions(const std::string& yaml_text, const std::string& what) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    ThrowError("{}: malformed YAML: {}", what, e.what());
  }
  TrackerOptions options;
  Apply(root, what, &options);
  try {
    options.Check();
  } catch (const Error& e) {
    ThrowError("{}: {}", what, e.what());
  }
  return options;
}

TrackerOptions LoadTrackerOptions(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    ThrowError("{}: cannot read the tracker options file", path);
  } catch (const YAML::Exception& e) {
    ThrowError("{}: malformed YAML: {}", path, e.what());
  }
  TrackerOptions options;
  Apply(root, path, &options);
  try {
    options.Check();
  } catch (const Error& e) {
    ThrowError("{}: {}", path, e.what());
  }
  return options;
}

}  // namespace unseen
