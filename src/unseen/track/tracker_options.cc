// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/tracker_options.h"

#include <cmath>
#include <map>

#include <yaml-cpp/yaml.h>

#include "unseen/util/error.h"
#include "unseen/util/yaml_options.h"

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
  UNSEEN_CHECK(
      photometric_coarse_min_update_px >= 0.0 && std::isfinite(photometric_coarse_min_update_px),
      "pyramid.photometric_coarse_min_update_px {} must be >= 0", photometric_coarse_min_update_px);
  UNSEEN_CHECK(noise_stop_chi2 >= 0.0 && std::isfinite(noise_stop_chi2),
               "pyramid.noise_stop_chi2 {} must be >= 0", noise_stop_chi2);
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
  UNSEEN_CHECK(max_finest_px == 0.0 || (max_finest_px >= 1024.0 && std::isfinite(max_finest_px)),
               "pyramid.max_finest_px {} must be 0 (no budget) or >= 1024", max_finest_px);
  UNSEEN_CHECK(finest_hysteresis > 0.0 && finest_hysteresis <= 1.0,
               "pyramid.finest_hysteresis {} must be in (0, 1]", finest_hysteresis);
}

void FailureOptions::Check() const {
  UNSEEN_CHECK(min_share >= 0.0 && good_share > min_share && good_share <= 1.0,
               "failure: need 0 <= min_share ({}) < good_share ({}) <= 1", min_share, good_share);
  UNSEEN_CHECK(silhouette_veto_ratio == 0.0 || (silhouette_veto_ratio > bad_region_residual_ratio &&
                                                 std::isfinite(silhouette_veto_ratio)),
               "failure.silhouette_veto_ratio {} must be 0 or above bad_region_residual_ratio ({})",
               silhouette_veto_ratio, bad_region_residual_ratio);
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
  UNSEEN_CHECK(vouched_reference_rate >= residual_reference_rate && vouched_reference_rate <= 1.0,
               "failure.vouched_reference_rate {} must be in [residual_reference_rate {}, 1]",
               vouched_reference_rate, residual_reference_rate);
  UNSEEN_CHECK(vouched_region_residual_ratio > 0.0 && std::isfinite(vouched_region_residual_ratio),
               "failure.vouched_region_residual_ratio {} must be > 0",
               vouched_region_residual_ratio);
  UNSEEN_CHECK(vouched_follow_ratio >= good_residual_ratio && std::isfinite(vouched_follow_ratio),
               "failure.vouched_follow_ratio {} must be >= good_residual_ratio = {}",
               vouched_follow_ratio, good_residual_ratio);
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
  UNSEEN_CHECK(occluded_region_share > 0.0 && occluded_region_share <= 1.0,
               "failure.occluded_region_share {} must be in (0, 1]", occluded_region_share);
  UNSEEN_CHECK(0.0 <= min_visible_fraction && min_visible_fraction < good_visible_fraction &&
                   good_visible_fraction <= 1.0,
               "failure: need 0 <= min_visible_fraction ({}) < good_visible_fraction ({}) <= 1",
               min_visible_fraction, good_visible_fraction);
  UNSEEN_CHECK(0.0 <= min_area_ratio && min_area_ratio < good_area_ratio && good_area_ratio <= 1.0,
               "failure: need 0 <= min_area_ratio ({}) < good_area_ratio ({}) <= 1",
               min_area_ratio, good_area_ratio);
  UNSEEN_CHECK(min_in_image_share > 0.0 && min_in_image_share <= 1.0,
               "failure.min_in_image_share {} must be in (0, 1]", min_in_image_share);
  UNSEEN_CHECK(area_memory_frames >= 0, "failure.area_memory_frames {} must be >= 0",
               area_memory_frames);
  UNSEEN_CHECK(lost_confidence >= 0.0 && lost_confidence <= 1.0,
               "failure.lost_confidence {} must be in [0, 1]", lost_confidence);
  UNSEEN_CHECK(recover_confidence >= lost_confidence && recover_confidence <= 1.0,
               "failure.recover_confidence {} must be in [lost_confidence = {}, 1]",
               recover_confidence, lost_confidence);
  UNSEEN_CHECK(recover_share_ratio >= 0.0 && recover_share_ratio <= 1.0,
               "failure.recover_share_ratio {} must be in [0, 1]", recover_share_ratio);
  UNSEEN_CHECK(lost_after_frames >= 1, "failure.lost_after_frames {} must be >= 1",
               lost_after_frames);
  UNSEEN_CHECK(coast_frames >= 0 && coast_frames <= 1000,
               "failure.coast_frames {} must be in [0, 1000]", coast_frames);
  UNSEEN_CHECK(search_offset > 0.0 && search_offset <= 10.0,
               "failure.search_offset {} must be in (0, 10]", search_offset);
  UNSEEN_CHECK(depth_vouch_agreement >= 0.0 && depth_vouch_agreement <= 1.0,
               "failure.depth_vouch_agreement {} must be in [0, 1]", depth_vouch_agreement);
  UNSEEN_CHECK(depth_vouch_min_measured >= 1, "failure.depth_vouch_min_measured {} must be >= 1",
               depth_vouch_min_measured);
  UNSEEN_CHECK(depth_vouch_max_region_ratio > 0.0 && std::isfinite(depth_vouch_max_region_ratio),
               "failure.depth_vouch_max_region_ratio {} must be > 0", depth_vouch_max_region_ratio);
  UNSEEN_CHECK(depth_vouch_min_line_share >= 0.0 && depth_vouch_min_line_share <= 1.0,
               "failure.depth_vouch_min_line_share {} must be in [0, 1]",
               depth_vouch_min_line_share);
  UNSEEN_CHECK(depth_vouch_confidence >= 0.0 && depth_vouch_confidence < recover_confidence,
               "failure.depth_vouch_confidence {} must be in [0, recover_confidence = {})",
               depth_vouch_confidence, recover_confidence);
}

void ReacquisitionOptions::Check() const {
  UNSEEN_CHECK(seed_object_px >= 8.0 && std::isfinite(seed_object_px),
               "reacquisition.seed_object_px {} must be >= 8", seed_object_px);
  UNSEEN_CHECK(search_radii > 0.0 && search_radii <= 20.0,
               "reacquisition.search_radii {} must be in (0, 20]", search_radii);
  UNSEEN_CHECK(seed_search_radii > 0.0 && seed_search_radii <= 20.0,
               "reacquisition.seed_search_radii {} must be in (0, 20]", seed_search_radii);
  UNSEEN_CHECK(min_correlation >= -1.0 && min_correlation <= 1.0,
               "reacquisition.min_correlation {} must be in [-1, 1]", min_correlation);
  UNSEEN_CHECK(max_seeds >= 1 && max_seeds <= 8, "reacquisition.max_seeds {} must be in [1, 8]",
               max_seeds);
  UNSEEN_CHECK(rotation_deg >= 0.0 && rotation_deg <= 90.0,
               "reacquisition.rotation_deg {} must be in [0, 90]", rotation_deg);
  UNSEEN_CHECK(max_candidates >= 0 && max_candidates <= 100,
               "reacquisition.max_candidates {} must be in [0, 100]", max_candidates);
  UNSEEN_CHECK(proposals >= 0 && proposals <= 32, "reacquisition.proposals {} must be in [0, 32]",
               proposals);
  UNSEEN_CHECK(accept_coasted_score >= 0.0 && std::isfinite(accept_coasted_score),
               "reacquisition.accept_coasted_score {} must be >= 0 (above 1: never)",
               accept_coasted_score);
  UNSEEN_CHECK(score_iterations >= 1 && score_iterations <= 100,
               "reacquisition.score_iterations {} must be in [1, 100]", score_iterations);
  UNSEEN_CHECK(score_levels >= 1 && score_levels <= 8,
               "reacquisition.score_levels {} must be in [1, 8]", score_levels);
  UNSEEN_CHECK(refine_candidates >= 0 && refine_candidates <= 100,
               "reacquisition.refine_candidates {} must be in [0, 100]", refine_candidates);
  UNSEEN_CHECK(refine_levels >= 0 && refine_levels <= 8,
               "reacquisition.refine_levels {} must be in [0, 8]", refine_levels);
  UNSEEN_CHECK(min_score >= 0.0 && min_score <= 1.0,
               "reacquisition.min_score {} must be in [0, 1]", min_score);
  UNSEEN_CHECK(quiet_candidates >= -1 && quiet_candidates <= 100,
               "reacquisition.quiet_candidates {} must be in [-1, 100]", quiet_candidates);
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
  UNSEEN_CHECK(dragged_open_ratio >= 0.0 && std::isfinite(dragged_open_ratio),
               "photometric.dragged_open_ratio {} must be >= 0", dragged_open_ratio);
  UNSEEN_CHECK(projected_with_depth_ratio > 0.0 && projected_with_depth_ratio <= 1.0,
               "photometric.projected_with_depth_ratio {} must be in (0, 1]",
               projected_with_depth_ratio);
  UNSEEN_CHECK(light_change_fit >= 0.0 && light_change_fit <= 1.0,
               "photometric.light_change_fit {} must be in [0, 1]", light_change_fit);
  UNSEEN_CHECK(light_change_max_gathering >= 0.0 && light_change_max_gathering <= 1.0,
               "photometric.light_change_max_gathering {} must be in [0, 1]",
               light_change_max_gathering);
  UNSEEN_CHECK(silhouette_drag_ratio >= 0.0 && std::isfinite(silhouette_drag_ratio),
               "photometric.silhouette_drag_ratio {} must be >= 0", silhouette_drag_ratio);
  UNSEEN_CHECK(silhouette_drag_max_share >= 0.0 && silhouette_drag_max_share <= 1.0,
               "photometric.silhouette_drag_max_share {} must be in [0, 1]",
               silhouette_drag_max_share);
  UNSEEN_CHECK(silhouette_drag_led_ratio >= 0.0 && std::isfinite(silhouette_drag_led_ratio),
               "photometric.silhouette_drag_led_ratio {} must be >= 0", silhouette_drag_led_ratio);
}

namespace {

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
  const std::map<std::string, YamlSection> sections = {
      {"photometric",
       {{"enabled", YamlField(&ph.enabled)},
        {"require_appearance", YamlField(&ph.require_appearance)},
        {"min_start_fit", YamlField(&ph.min_start_fit)},
        {"start_by_silhouette", YamlField(&ph.start_by_silhouette)},
        {"start_drag_px", YamlField(&ph.start_drag_px)},
        {"start_drag_ratio", YamlField(&ph.start_drag_ratio)},
        {"dragged_weight", YamlField(&ph.dragged_weight)},
        {"dragged_open_ratio", YamlField(&ph.dragged_open_ratio)},
        {"projected_with_depth_ratio", YamlField(&ph.projected_with_depth_ratio)},
        {"light_change_fit", YamlField(&ph.light_change_fit)},
        {"light_change_max_gathering", YamlField(&ph.light_change_max_gathering)},
        {"silhouette_drag_ratio", YamlField(&ph.silhouette_drag_ratio)},
        {"silhouette_drag_max_share", YamlField(&ph.silhouette_drag_max_share)},
        {"silhouette_drag_led_ratio", YamlField(&ph.silhouette_drag_led_ratio)},
        {"weight", YamlField(&ph.weight)}}},
      {"preprocess",
       {{"use_linf", YamlField(&pp.use_linf)},
        {"linf_sigma_px", YamlField(&pp.linf_sigma_px)},
        {"min_linf_sigma_px", YamlField(&pp.min_linf_sigma_px)},
        {"linf_epsilon", YamlField(&pp.linf_epsilon)},
        {"blur_sigma_px", YamlField(&pp.blur_sigma_px)},
        {"shading_transfer", YamlField(&pp.shading_transfer)},
        {"shading_sigma_px", YamlField(&pp.shading_sigma_px)},
        {"silhouette_gamma", YamlField(&pp.silhouette_gamma)},
        {"background_band_px", YamlField(&pp.background_band_px)},
        {"background_sigma_px", YamlField(&pp.background_sigma_px)}}},
      {"selection",
       {{"color_mode", YamlEnumField(&se.color_mode, &ParseColorMode)},
        {"use_gradient_threshold", YamlField(&se.use_gradient_threshold)},
        {"min_gradient_sq", YamlField(&se.min_gradient_sq)},
        {"use_normal_flow_bound", YamlField(&se.use_normal_flow_bound)},
        {"max_normal_flow_px", YamlField(&se.max_normal_flow_px)},
        {"use_occlusion_rejection", YamlField(&se.use_occlusion_rejection)},
        {"occlusion_min_gradient_sq", YamlField(&se.occlusion_min_gradient_sq)},
        {"occlusion_max_angle_rad", YamlField(&se.occlusion_max_angle_rad)},
        {"occlusion_max_magnitude_diff", YamlField(&se.occlusion_max_magnitude_diff)},
        {"min_eigen_ratio", YamlField(&se.min_eigen_ratio)},
        {"block_px", YamlField(&se.block_px)},
        {"block_min_gradient", YamlField(&se.block_min_gradient)},
        {"block_min_share_ratio", YamlField(&se.block_min_share_ratio)},
        {"block_min_blocks", YamlField(&se.block_min_blocks)}}},
      {"solver",
       {{"kernel", YamlEnumField(&so.kernel, &ParseRobustKernel)},
        {"kernel_width", YamlField(&so.kernel_width)},
        {"irls_iterations", YamlField(&so.irls_iterations)},
        {"min_scale_px", YamlField(&so.min_scale_px)},
        {"min_equations", YamlField(&so.min_equations)},
        {"damping", YamlField(&so.damping)}}},
      {"pyramid",
       {{"max_levels", YamlField(&py.max_levels)},
        {"min_object_px", YamlField(&py.min_object_px)},
        {"max_iterations_per_level", YamlField(&py.max_iterations_per_level)},
        {"min_update_px", YamlField(&py.min_update_px)},
        {"coarse_max_iterations", YamlField(&py.coarse_max_iterations)},
        {"coarse_min_update_px", YamlField(&py.coarse_min_update_px)},
        {"photometric_coarse_min_update_px", YamlField(&py.photometric_coarse_min_update_px)},
        {"noise_stop_chi2", YamlField(&py.noise_stop_chi2)},
        {"max_step_px", YamlField(&py.max_step_px)},
        {"resample_iterations", YamlField(&py.resample_iterations)},
        {"rerender_px", YamlField(&py.rerender_px)},
        {"resample_margin_px", YamlField(&py.resample_margin_px)},
        {"rim_px", YamlField(&py.rim_px)},
        {"supersampled_levels", YamlField(&py.supersampled_levels)},
        {"max_finest_px", YamlField(&py.max_finest_px)},
        {"finest_hysteresis", YamlField(&py.finest_hysteresis)},
        {"adaptive_levels", YamlField(&py.adaptive_levels)},
        {"min_adaptive_levels", YamlField(&py.min_adaptive_levels)},
        {"capture_px", YamlField(&py.capture_px)},
        {"prediction_margin", YamlField(&py.prediction_margin)},
        {"correction_decay", YamlField(&py.correction_decay)}}},
      {"predictor",
       {{"type", YamlEnumField(&pr.type, &ParsePredictorType)},
        {"linear_accel_sigma", YamlField(&pr.linear_accel_sigma)},
        {"angular_accel_sigma", YamlField(&pr.angular_accel_sigma)},
        {"position_sigma", YamlField(&pr.position_sigma)},
        {"rotation_sigma", YamlField(&pr.rotation_sigma)},
        {"min_confidence", YamlField(&pr.min_confidence)},
        {"confidence_power", YamlField(&pr.confidence_power)}}},
      {"failure",
       {{"min_share", YamlField(&fa.min_share)},
        {"good_share", YamlField(&fa.good_share)},
        {"min_used_px", YamlField(&fa.min_used_px)},
        {"good_used_px", YamlField(&fa.good_used_px)},
        {"good_residual_px", YamlField(&fa.good_residual_px)},
        {"good_residual_ratio", YamlField(&fa.good_residual_ratio)},
        {"bad_residual_ratio", YamlField(&fa.bad_residual_ratio)},
        {"residual_reference_rate", YamlField(&fa.residual_reference_rate)},
        {"vouched_reference_rate", YamlField(&fa.vouched_reference_rate)},
        {"vouched_region_residual_ratio", YamlField(&fa.vouched_region_residual_ratio)},
        {"vouched_follow_ratio", YamlField(&fa.vouched_follow_ratio)},
        {"min_reference_residual_px", YamlField(&fa.min_reference_residual_px)},
        {"bad_residual_px", YamlField(&fa.bad_residual_px)},
        {"good_update_px", YamlField(&fa.good_update_px)},
        {"bad_update_px", YamlField(&fa.bad_update_px)},
        {"min_pixels", YamlField(&fa.min_pixels)},
        {"good_region_residual_ratio", YamlField(&fa.good_region_residual_ratio)},
        {"bad_region_residual_ratio", YamlField(&fa.bad_region_residual_ratio)},
        {"silhouette_veto_ratio", YamlField(&fa.silhouette_veto_ratio)},
        {"occluded_region_share", YamlField(&fa.occluded_region_share)},
        {"min_reference_region_residual", YamlField(&fa.min_reference_region_residual)},
        {"min_region_lines", YamlField(&fa.min_region_lines)},
        {"min_visible_fraction", YamlField(&fa.min_visible_fraction)},
        {"good_visible_fraction", YamlField(&fa.good_visible_fraction)},
        {"min_area_ratio", YamlField(&fa.min_area_ratio)},
        {"good_area_ratio", YamlField(&fa.good_area_ratio)},
        {"min_in_image_share", YamlField(&fa.min_in_image_share)},
        {"area_memory_frames", YamlField(&fa.area_memory_frames)},
        {"depth_vouch_agreement", YamlField(&fa.depth_vouch_agreement)},
        {"depth_vouch_min_measured", YamlField(&fa.depth_vouch_min_measured)},
        {"depth_vouch_max_region_ratio", YamlField(&fa.depth_vouch_max_region_ratio)},
        {"depth_vouch_min_line_share", YamlField(&fa.depth_vouch_min_line_share)},
        {"depth_vouch_confidence", YamlField(&fa.depth_vouch_confidence)},
        {"lost_confidence", YamlField(&fa.lost_confidence)},
        {"lost_after_frames", YamlField(&fa.lost_after_frames)},
        {"recover_confidence", YamlField(&fa.recover_confidence)},
        {"recover_share_ratio", YamlField(&fa.recover_share_ratio)},
        {"search_when_lost", YamlField(&fa.search_when_lost)},
        {"coast_frames", YamlField(&fa.coast_frames)},
        {"search_offset", YamlField(&fa.search_offset)}}},
      {"reacquisition",
       {{"use_correlation", YamlField(&re.use_correlation)},
        {"colour_correlation", YamlField(&re.colour_correlation)},
        {"seed_object_px", YamlField(&re.seed_object_px)},
        {"search_radii", YamlField(&re.search_radii)},
        {"seed_search_radii", YamlField(&re.seed_search_radii)},
        {"min_correlation", YamlField(&re.min_correlation)},
        {"max_seeds", YamlField(&re.max_seeds)},
        {"rotation_deg", YamlField(&re.rotation_deg)},
        {"max_candidates", YamlField(&re.max_candidates)},
        {"proposals", YamlField(&re.proposals)},
        {"accept_coasted_score", YamlField(&re.accept_coasted_score)},
        {"turn_in_place", YamlField(&re.turn_in_place)},
        {"score_iterations", YamlField(&re.score_iterations)},
        {"score_levels", YamlField(&re.score_levels)},
        {"refine_candidates", YamlField(&re.refine_candidates)},
        {"refine_levels", YamlField(&re.refine_levels)},
        {"min_score", YamlField(&re.min_score)},
        {"quiet_candidates", YamlField(&re.quiet_candidates)},
        {"seed_when_doubtful", YamlField(&re.seed_when_doubtful)},
        {"doubtful_confidence", YamlField(&re.doubtful_confidence)},
        {"min_seed_shift_px", YamlField(&re.min_seed_shift_px)}}},
      {"depth",
       {{"enabled", YamlField(&de.enabled)},
        {"max_points", YamlField(&de.max_points)},
        {"max_distance_m", YamlField(&de.max_distance_m)},
        {"occluder_margin_m", YamlField(&de.occluder_margin_m)},
        {"occluder_margin_sigmas", YamlField(&de.occluder_margin_sigmas)},
        {"roughness_noise_factor", YamlField(&de.roughness_noise_factor)},
        {"occluder_slope_px", YamlField(&de.occluder_slope_px)},
        {"kernel", YamlEnumField(&de.residual.kernel, &ParseRobustKernel)},
        {"kernel_width", YamlField(&de.residual.kernel_width)},
        {"min_scale_m", YamlField(&de.residual.min_scale)},
        {"min_noise_m", YamlField(&de.residual.min_noise)},
        {"max_noise_m", YamlField(&de.residual.max_noise)},
        {"damping", YamlField(&de.residual.damping)},
        {"weight", YamlField(&de.residual.weight)},
        {"agree_distance_m", YamlField(&de.agree_distance_m)},
        {"bad_agreement", YamlField(&de.bad_agreement)},
        {"good_agreement", YamlField(&de.good_agreement)},
        {"min_measured", YamlField(&de.min_measured)},
        {"max_hidden_share", YamlField(&de.max_hidden_share)},
        {"coarse_with_own_texture", YamlField(&de.coarse_with_own_texture)},
        {"retry_doubtful_with_coarse_depth", YamlField(&de.retry_doubtful_with_coarse_depth)}}},
      {"region",
       {{"enabled", YamlField(&rg.enabled)},
        {"bins_per_channel", YamlField(&rg.bins_per_channel)},
        {"max_lines", YamlField(&rg.max_lines)},
        {"line_px", YamlField(&rg.line_px)},
        {"foreground_margin_px", YamlField(&rg.foreground_margin_px)},
        {"background_margin_px", YamlField(&rg.background_margin_px)},
        {"learn_rate", YamlField(&rg.learn_rate)},
        {"min_sigma_px", YamlField(&rg.min_sigma_px)},
        {"max_sigma_px", YamlField(&rg.max_sigma_px)},
        {"min_contrast", YamlField(&rg.min_contrast)},
        {"skip_occluded_lines", YamlField(&rg.skip_occluded_lines)},
        {"occluded_probe_px", YamlField(&rg.occluded_probe_px)},
        {"edge_contradiction_px", YamlField(&rg.edge_contradiction_px)},
        {"skip_overrun_lines", YamlField(&rg.skip_overrun_lines)},
        {"kernel", YamlEnumField(&rg.residual.kernel, &ParseRobustKernel)},
        {"kernel_width", YamlField(&rg.residual.kernel_width)},
        {"min_scale", YamlField(&rg.residual.min_scale)},
        {"min_noise", YamlField(&rg.residual.min_noise)},
        {"max_noise", YamlField(&rg.residual.max_noise)},
        {"damping", YamlField(&rg.residual.damping)},
        {"weight", YamlField(&rg.residual.weight)},
        {"bad_agreement", YamlField(&rg.bad_agreement)},
        {"good_agreement", YamlField(&rg.good_agreement)},
        {"min_start_edge_share", YamlField(&rg.min_start_edge_share)}}},
      {"live_appearance",
       {{"enabled", YamlField(&la.enabled)},
        {"when_silhouette_fails", YamlField(&la.when_silhouette_fails)},
        {"first_overrun_share", YamlField(&la.first_overrun_share)},
        {"print_share", YamlField(&la.print_share)},
        {"print_min_gradient", YamlField(&la.print_min_gradient)},
        {"print_inset_px", YamlField(&la.print_inset_px)},
        {"always", YamlField(&la.always)},
        {"min_confidence", YamlField(&la.min_confidence)},
        {"refresh_frames", YamlField(&la.refresh_frames)},
        {"refresh_share_ratio", YamlField(&la.refresh_share_ratio)},
        {"margin_px", YamlField(&la.margin_px)},
        {"occlusion_tolerance", YamlField(&la.occlusion_tolerance)},
        {"photometric_weight", YamlField(&la.photometric_weight)},
        {"poor_fit_share", YamlField(&la.poor_fit_share)},
        {"poor_fit_frames", YamlField(&la.poor_fit_frames)},
        {"poor_fit_best_share", YamlField(&la.poor_fit_best_share)},
        {"poor_fit_confidence", YamlField(&la.poor_fit_confidence)},
        {"replace_after_light_change", YamlField(&la.replace_after_light_change)}}},
      {"simplify",
       {{"enabled", YamlField(&si.enabled)},
        {"max_normal_angle_rad", YamlField(&si.max_normal_angle_rad)},
        {"relative_tolerance", YamlField(&si.relative_tolerance)},
        {"attribute_tolerance", YamlField(&si.attribute_tolerance)},
        {"texture_shift_tolerance", YamlField(&si.texture_shift_tolerance)}}},
  };
  UNSEEN_CHECK(root.IsMap(), "{}: expected a map at the top level", what);
  for (const auto& kv : root) {
    const std::string key = YamlKeyName(kv.first, what);
    if (key == "frame_interval_s") {
      YamlField(&o->frame_interval_s)(kv.second, what + ": " + key);
      continue;
    }
    if (key == "threads") {
      YamlField(&o->threads)(kv.second, what + ": " + key);
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
    ApplyYamlSection(kv.second, what + ": " + key, it->second);
  }
}

}  // namespace

TrackerOptions ParseTrackerOptions(const std::string& yaml_text, const std::string& what) {
  const YAML::Node root = ParseYamlText(yaml_text, what);
  TrackerOptions options;
  Apply(root, what, &options);
  CheckOptionsFrom(options, what);
  return options;
}

TrackerOptions LoadTrackerOptions(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path, "tracker options");
  TrackerOptions options;
  Apply(root, path, &options);
  CheckOptionsFrom(options, path);
  return options;
}

}  // namespace unseen
