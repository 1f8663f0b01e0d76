// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/tracker_options.h"

#include <cstdio>
#include <fstream>

#include <gtest/gtest.h>

#include "unseen/util/error.h"

namespace unseen {
namespace {

TEST(TrackerOptions, DefaultsAreTheThesisValues) {
  const TrackerOptions o;
  EXPECT_NO_THROW(o.Check());
  EXPECT_DOUBLE_EQ(o.preprocess.blur_sigma_px, 1.8);
  EXPECT_DOUBLE_EQ(o.selection.max_normal_flow_px, 1.22);
  EXPECT_DOUBLE_EQ(o.selection.min_gradient_sq, 984e-6);
  EXPECT_DOUBLE_EQ(o.selection.occlusion_min_gradient_sq, 98.4e-6);
  EXPECT_DOUBLE_EQ(o.selection.occlusion_max_angle_rad, 0.90);
  EXPECT_DOUBLE_EQ(o.selection.occlusion_max_magnitude_diff, 39.2e-3);
  EXPECT_EQ(o.selection.color_mode, ColorMode::kColorGradientRedundancy);
}

TEST(TrackerOptions, TheDimFootageConfigEstimatesTheBackgroundBesideTheSilhouette) {
  const TrackerOptions o =
      LoadTrackerOptions(std::string(UNSEEN_SOURCE_DIR) + "/configs/tracker/dim_footage.yaml");
  EXPECT_EQ(o.preprocess.background_band_px, 2);
  EXPECT_EQ(o.pyramid.rim_px, 2);
  EXPECT_EQ(TrackerOptions().preprocess.background_band_px, 0);  // not the default
}

TEST(TrackerOptions, ParsesYamlOverTheDefaults) {
  const TrackerOptions o = ParseTrackerOptions(
      "preprocess: {use_linf: false, blur_sigma_px: 2.5, background_band_px: 3,\n"
      "             background_sigma_px: 4}\n"
      "selection: {color_mode: raw, use_occlusion_rejection: false, block_min_share_ratio: 0}\n"
      "solver: {kernel: tukey, kernel_width: 4.685}\n"
      "pyramid: {max_levels: 2, adaptive_levels: false, min_adaptive_levels: 1, capture_px: 3,\n"
      "          photometric_coarse_min_update_px: 0.5, max_finest_px: 40000,\n"
      "          finest_hysteresis: 0.5, noise_stop_chi2: 0}\n"
      "predictor: {type: none, min_confidence: 0.4, confidence_power: 2}\n"
      "failure: {lost_after_frames: 5, good_used_px: 3000, bad_residual_ratio: 2.0,\n"
      "          vouched_reference_rate: 0.5, vouched_region_residual_ratio: 1.2}\n"
      "frame_interval_s: 0.04\n"
      "threads: 2\n");
  EXPECT_FALSE(o.preprocess.use_linf);
  EXPECT_EQ(o.threads, 2);
  EXPECT_DOUBLE_EQ(o.preprocess.blur_sigma_px, 2.5);
  EXPECT_EQ(o.preprocess.background_band_px, 3);
  EXPECT_DOUBLE_EQ(o.preprocess.background_sigma_px, 4.0);
  EXPECT_EQ(o.selection.color_mode, ColorMode::kRawColor);
  EXPECT_FALSE(o.selection.use_occlusion_rejection);
  EXPECT_EQ(o.solver.kernel, RobustKernel::kTukey);
  EXPECT_EQ(o.pyramid.max_levels, 2);
  EXPECT_FALSE(o.pyramid.adaptive_levels);
  EXPECT_EQ(o.pyramid.min_adaptive_levels, 1);
  EXPECT_EQ(o.pyramid.capture_px, 3.0);
  EXPECT_DOUBLE_EQ(o.pyramid.photometric_coarse_min_update_px, 0.5);
  EXPECT_DOUBLE_EQ(o.pyramid.max_finest_px, 40000.0);
  EXPECT_DOUBLE_EQ(o.pyramid.finest_hysteresis, 0.5);
  EXPECT_DOUBLE_EQ(o.pyramid.noise_stop_chi2, 0.0);
  EXPECT_DOUBLE_EQ(o.pyramid.coarse_min_update_px, 0.3);  // untouched default
  EXPECT_EQ(o.predictor.type, PredictorType::kHold);
  EXPECT_DOUBLE_EQ(o.predictor.min_confidence, 0.4);
  EXPECT_DOUBLE_EQ(o.predictor.confidence_power, 2.0);
  EXPECT_EQ(o.failure.lost_after_frames, 5);
  EXPECT_DOUBLE_EQ(o.failure.good_used_px, 3000);
  EXPECT_DOUBLE_EQ(o.failure.bad_residual_ratio, 2.0);
  EXPECT_DOUBLE_EQ(o.failure.vouched_reference_rate, 0.5);
  EXPECT_DOUBLE_EQ(o.failure.vouched_region_residual_ratio, 1.2);
  EXPECT_DOUBLE_EQ(o.selection.block_min_share_ratio, 0.0);
  EXPECT_DOUBLE_EQ(o.frame_interval_s, 0.04);
  EXPECT_DOUBLE_EQ(o.selection.max_normal_flow_px, 1.22);  // untouched default
}

TEST(TrackerOptions, ParsesTheReacquisitionSection) {
  const TrackerOptions o = ParseTrackerOptions(
      "reacquisition: {use_correlation: false, seed_object_px: 32, search_radii: 6,\n"
      "  min_correlation: 0.4, max_seeds: 3, rotation_deg: 20, max_candidates: 10,\n"
      "  accept_coasted_score: 0.9,\n"
      "  score_levels: 2, score_iterations: 4, refine_candidates: 3, refine_levels: 3,\n"
      "  min_score: 0.1, quiet_candidates: -1, turn_in_place: false,\n"
      "  seed_when_doubtful: false, doubtful_confidence: 0.4, min_seed_shift_px: 2}\n");
  const ReacquisitionOptions& r = o.reacquisition;
  EXPECT_FALSE(r.use_correlation);
  EXPECT_DOUBLE_EQ(r.seed_object_px, 32.0);
  EXPECT_DOUBLE_EQ(r.search_radii, 6.0);
  EXPECT_DOUBLE_EQ(r.min_correlation, 0.4);
  EXPECT_EQ(r.max_seeds, 3);
  EXPECT_DOUBLE_EQ(r.rotation_deg, 20.0);
  EXPECT_EQ(r.max_candidates, 10);
  EXPECT_DOUBLE_EQ(r.accept_coasted_score, 0.9);
  EXPECT_EQ(r.score_levels, 2);
  EXPECT_EQ(r.score_iterations, 4);
  EXPECT_EQ(r.refine_candidates, 3);
  EXPECT_EQ(r.refine_levels, 3);
  EXPECT_DOUBLE_EQ(r.min_score, 0.1);
  EXPECT_EQ(r.quiet_candidates, -1);
  EXPECT_FALSE(r.turn_in_place);
  EXPECT_FALSE(r.seed_when_doubtful);
  EXPECT_DOUBLE_EQ(r.doubtful_confidence, 0.4);
  EXPECT_DOUBLE_EQ(r.min_seed_shift_px, 2.0);
  EXPECT_TRUE(ParseTrackerOptions("").reacquisition.use_correlation);  // default
  EXPECT_THROW(ParseTrackerOptions("preprocess: {background_band_px: -1}"), Error);
  EXPECT_THROW(ParseTrackerOptions("preprocess: {background_sigma_px: 0}"), Error);
  EXPECT_THROW(ParseTrackerOptions("reacquisition: {max_seeds: 0}"), Error);
  EXPECT_THROW(ParseTrackerOptions("reacquisition: {rotation_deg: -5}"), Error);
  EXPECT_THROW(ParseTrackerOptions("reacquisition: {score_levels: 0}"), Error);
  EXPECT_THROW(ParseTrackerOptions("reacquisition: {score_iterations: 0}"), Error);
  EXPECT_THROW(ParseTrackerOptions("reacquisition: {refine_levels: -1}"), Error);
  EXPECT_THROW(ParseTrackerOptions("reacquisition: {quiet_candidates: -2}"), Error);
  EXPECT_THROW(ParseTrackerOptions("reacquisition: {accept_coasted_score: -0.1}"), Error);
  EXPECT_THROW(ParseTrackerOptions("reacquisition: {doubtful_confidence: 1.5}"), Error);
  EXPECT_DOUBLE_EQ(
      ParseTrackerOptions("failure: {depth_vouch_agreement: 0.8}").failure.depth_vouch_agreement,
      0.8);
  EXPECT_THROW(ParseTrackerOptions("failure: {depth_vouch_agreement: 1.5}"), Error);
  EXPECT_THROW(ParseTrackerOptions("failure: {depth_vouch_min_measured: 0}"), Error);
  EXPECT_THROW(ParseTrackerOptions("failure: {depth_vouch_max_region_ratio: 0}"), Error);
  EXPECT_THROW(ParseTrackerOptions("failure: {depth_vouch_min_line_share: -0.1}"), Error);
  // A vouched frame must not re-acquire a lost object.
  EXPECT_THROW(ParseTrackerOptions("failure: {depth_vouch_confidence: 0.5}"), Error);
  EXPECT_DOUBLE_EQ(
      ParseTrackerOptions("failure: {min_in_image_share: 1}").failure.min_in_image_share, 1.0);
  EXPECT_THROW(ParseTrackerOptions("failure: {min_in_image_share: 0}"), Error);
  EXPECT_THROW(ParseTrackerOptions("failure: {min_in_image_share: 1.2}"), Error);
  EXPECT_THROW(ParseTrackerOptions("reacquisition: {search_radius: 3}"), Error);  // unknown
}

TEST(TrackerOptions, ParsesTheModalitySections) {
  const TrackerOptions o = ParseTrackerOptions(
      "region: {weight: 0.7, max_noise: 1.5}\n"
      "depth: {max_noise_m: 0.01, coarse_with_own_texture: true, "
      "retry_doubtful_with_coarse_depth: false}\n"
      "live_appearance: {enabled: true, always: true, refresh_frames: 3, "
      "photometric_weight: 0.2}\n");
  EXPECT_DOUBLE_EQ(o.region.residual.weight, 0.7);
  EXPECT_DOUBLE_EQ(o.region.residual.max_noise, 1.5);
  EXPECT_DOUBLE_EQ(o.depth.residual.max_noise, 0.01);
  EXPECT_TRUE(o.depth.coarse_with_own_texture);
  EXPECT_FALSE(ParseTrackerOptions("").depth.coarse_with_own_texture);  // default
  EXPECT_FALSE(o.depth.retry_doubtful_with_coarse_depth);
  EXPECT_TRUE(ParseTrackerOptions("").depth.retry_doubtful_with_coarse_depth);  // default
  EXPECT_TRUE(o.live_appearance.enabled);
  EXPECT_TRUE(o.live_appearance.always);
  EXPECT_EQ(o.live_appearance.refresh_frames, 3);
  EXPECT_DOUBLE_EQ(o.live_appearance.photometric_weight, 0.2);
  EXPECT_FALSE(ParseTrackerOptions("").live_appearance.enabled);  // default
  EXPECT_THROW(ParseTrackerOptions("region: {max_noise: 0.1}"), Error);  // below min_noise
  EXPECT_THROW(ParseTrackerOptions("live_appearance: {refresh_frames: 0}"), Error);
  EXPECT_THROW(ParseTrackerOptions("live_appearance: {every: 2}"), Error);  // unknown
}

TEST(TrackerOptions, RejectsBadFilesNamingTheKey) {
  auto message = [](const std::string& yaml) {
    try {
      ParseTrackerOptions(yaml, "t.yaml");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message("pyramid: {max_levles: 2}").find("max_levles"), std::string::npos);
  EXPECT_NE(message("colour: {}").find("colour"), std::string::npos);
  EXPECT_NE(message("pyramid: {max_levels: two}").find("pyramid.max_levels"), std::string::npos);
  EXPECT_NE(message("pyramid: {max_levels: 0}").find("max_levels"), std::string::npos);
  EXPECT_NE(message("threads: -1").find("threads"), std::string::npos);
  EXPECT_NE(message("pyramid: {max_levels: 2, min_adaptive_levels: 3}").find("min_adaptive_levels"),
            std::string::npos);
  EXPECT_NE(message("selection: {color_mode: hsv}").find("hsv"), std::string::npos);
  EXPECT_NE(message("pyramid: {resample_iterations: -1}").find("pyramid.resample_iterations"),
            std::string::npos);
  EXPECT_NE(message("pyramid: {rerender_px: .nan}").find("pyramid.rerender_px"), std::string::npos);
  EXPECT_NE(message("pyramid: {max_finest_px: 100}").find("pyramid.max_finest_px"),
            std::string::npos);
  EXPECT_NE(message("pyramid: {finest_hysteresis: 0}").find("pyramid.finest_hysteresis"),
            std::string::npos);
  EXPECT_NE(message("pyramid: {noise_stop_chi2: -1}").find("pyramid.noise_stop_chi2"),
            std::string::npos);
  EXPECT_NE(message("pyramid: {photometric_coarse_min_update_px: -1}")
                .find("pyramid.photometric_coarse_min_update_px"),
            std::string::npos);
  EXPECT_NE(message("pyramid: {resample_margin_px: 100}").find("pyramid.resample_margin_px"),
            std::string::npos);
  EXPECT_NE(message("failure: {min_area_ratio: 0.5, good_area_ratio: 0.4}").find("min_area_ratio"),
            std::string::npos);
  EXPECT_NE(message("failure: {vouched_reference_rate: 0.05}").find("failure.vouched_reference_rate"),
            std::string::npos);
  EXPECT_NE(message("failure: {vouched_region_residual_ratio: 0}")
                .find("failure.vouched_region_residual_ratio"),
            std::string::npos);
  EXPECT_NE(message("failure: {vouched_follow_ratio: 1.1}").find("failure.vouched_follow_ratio"),
            std::string::npos);
  EXPECT_NE(message("failure: {recover_share_ratio: 2}").find("failure.recover_share_ratio"),
            std::string::npos);
  EXPECT_NE(message("failure: {area_memory_frames: -2}").find("failure.area_memory_frames"),
            std::string::npos);
  EXPECT_NE(message("a: [").find("t.yaml"), std::string::npos);
  EXPECT_THROW(LoadTrackerOptions("/nonexistent/tracker.yaml"), Error);
}

TEST(TrackerOptions, LoadsAFile) {
  const std::string path = ::testing::TempDir() + "/tracker_options_test.yaml";
  {
    std::ofstream out(path);
    out << "solver:\n  irls_iterations: 4\n";
  }
  EXPECT_EQ(LoadTrackerOptions(path).solver.irls_iterations, 4);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace unseen
