// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// How the tracker judges an alignment: the photometric fit, the confidence every modality
// vouches for, and the first frame's checks that the model's appearance fits the image.
#include "unseen/track/tracker.h"

#include <algorithm>
#include <vector>

#include "unseen/util/logging.h"

namespace unseen {
namespace {

double Ramp(double value, double zero_at, double one_at) {
  const double t = (value - zero_at) / (one_at - zero_at);
  return std::clamp(t, 0.0, 1.0);
}

}  // namespace

double Tracker::PhotometricFit(const SolveSummary& s, bool with_references,
                               double silhouette_term) const {
  const FailureOptions& f = options_.failure;
  if (s.counts.used < f.min_pixels) return 0.0;
  // Used pixels in level-0 pixels: a large object aligned at a coarser finest level
  // (PyramidOptions::max_finest_px) is as well supported as at level 0.
  const double used_px = double(s.counts.used) * double(1 << (2 * s.finest_level));
  double support_term = std::max(Ramp(s.share, f.min_share, f.good_share),
                                 Ramp(used_px, f.min_used_px, f.good_used_px));
  if (f.min_visible_fraction > 0.0 && silhouette_term > 0.0 && s.counts.occluded_gradient > 0) {
    // Texture behind an occluder (whole blocks that failed the occlusion tests together)
    // cannot support the pose: where the silhouette vouches for it, the share counts the
    // visible texture, while enough of it is visible.
    const double gradient = double(s.counts.gradient_pixels());
    const double visible = double(s.counts.visible_gradient_pixels());
    if (visible > 0.0 && gradient > 0.0) {
      support_term = std::max(
          support_term,
          silhouette_term * Ramp(double(s.counts.used) / visible, f.min_share, f.good_share) *
              Ramp(visible / gradient, f.min_visible_fraction, f.good_visible_fraction));
    }
  }
  double residual_term = Ramp(s.initial_residual_px, f.bad_residual_px, f.good_residual_px);
  if (with_references && residual_reference_px_ > 0.0) {
    const double reference = std::max(residual_reference_px_, f.min_reference_residual_px);
    residual_term *= Ramp(s.initial_residual_px / reference, f.bad_residual_ratio,
                          f.good_residual_ratio);
  }
  const double update_term = Ramp(s.last_update_px, f.bad_update_px, f.good_update_px);
  return support_term * residual_term * update_term;
}

double Tracker::Confidence(const SolveSummary& s, bool with_references) const {
  const FailureOptions& f = options_.failure;
  if (s.equations < f.min_pixels) return 0.0;
  double area_term = 1.0;
  if (with_references && area_reference_px_ > 0.0 && s.object_px > 0.0) {
    const double ratio = s.object_px / area_reference_px_;
    area_term = Ramp(std::min(ratio, 1.0 / ratio), f.min_area_ratio, f.good_area_ratio);
  }
  return area_term * ModalityConfidence(s, with_references);
}

double Tracker::ModalityConfidence(const SolveSummary& s, bool with_references) const {
  const FailureOptions& f = options_.failure;
  // The silhouette judges the frame of a model without appearance; with measured depth to
  // guard it, it also vouches for a frame whose texture says little (motion blur). Measured
  // depth, when there is some, must agree in every case.
  double region_term = 0.0;
  double agreement_term = 0.0, residual_term = 1.0;  // region_term's two factors
  const double region_agreement = s.region_counts.Agreement();
  if (region_agreement >= 0.0 && s.region_counts.used >= f.min_region_lines) {
    agreement_term =
        Ramp(region_agreement, options_.region.bad_agreement, options_.region.good_agreement);
    if (with_references && region_residual_reference_ > 0.0) {
      residual_term = Ramp(RegionResidualRatio(s), f.bad_region_residual_ratio,
                           f.good_region_residual_ratio);
    }
    region_term = agreement_term * residual_term;
  }
  double photometric =
      PhotometricJudges() ? PhotometricFit(s, with_references, region_term) : 0.0;
  if (f.silhouette_veto_ratio > 0.0 && with_references && region_residual_reference_ > 0.0 &&
      region_agreement >= 0.0 && s.region_counts.used >= f.min_region_lines) {
    // A silhouette far off its contour contradicts what the texture vouches for.
    photometric *= Ramp(RegionResidualRatio(s), f.silhouette_veto_ratio,
                        f.bad_region_residual_ratio);
  }
  const double depth_agreement = s.depth_counts.Agreement(options_.depth);
  if (depth_agreement < 0.0) {
    // Colours taken from the tracked frames vouch for the frame-to-frame fit only; the
    // silhouette, which judged these models before they had colours, still may.
    if (live_appearance_) return std::max(photometric, region_term);
    return PhotometricJudges() ? photometric : region_term;
  }
  const double depth_term =
      Ramp(depth_agreement, options_.depth.bad_agreement, options_.depth.good_agreement);
  // Depth alone (no image modality in use) judges by itself.
  const bool image_judges = PhotometricJudges() || options_.region.enabled;
  if (!image_judges) return depth_term;
  // The silhouette judges only as far as its colours tell the object from its surroundings:
  // lines whose colours do not (too little contrast, an unsure contour) gave no row. Where
  // few did (a white object on white paper), its low agreement is its colours', not a
  // contradiction, and the measured depth judges in its place. Not so a contour the lines
  // that did give rows find far off (the residual against the confident frames'): those
  // contradict the pose whatever the others say (the real cube every third frame: 110 mm
  // off, 61 of 200 lines used at 10x their residual, the texture agreeing on 1 % of its
  // pixels, the depth on the part not hidden, was reported tracking at 0.70).
  double silhouette = region_term;
  if (s.region_counts.lines > 0) {
    const double informative = double(s.region_counts.used) / double(s.region_counts.lines);
    silhouette = residual_term * (1.0 - informative * (1.0 - agreement_term));
  }
  const double confidence = depth_term * std::max(photometric, silhouette);
  return with_references && DepthVouches(s) ? std::max(confidence, f.depth_vouch_confidence)
                                            : confidence;
}

bool Tracker::DepthVouches(const SolveSummary& s) const {
  const FailureOptions& f = options_.failure;
  const DepthCounts& depth = s.depth_counts;
  if (f.depth_vouch_agreement <= 0.0 || depth.measured < f.depth_vouch_min_measured ||
      double(depth.agreeing) < f.depth_vouch_agreement * double(depth.measured)) {
    return false;
  }
  // The silhouette seen and on its contour: depth alone is fooled by a support plane.
  const RegionCounts& lines = s.region_counts;
  return options_.region.enabled && lines.used >= f.min_region_lines &&
         double(lines.used) >= f.depth_vouch_min_line_share * double(lines.lines) &&
         region_residual_reference_ > 0.0 &&
         RegionResidualRatio(s) <= f.depth_vouch_max_region_ratio;
}

double Tracker::RegionResidualRatio(const SolveSummary& s) const {
  if (region_residual_reference_ <= 0.0) return 0.0;
  return s.region_residual /
         std::max(region_residual_reference_, options_.failure.min_reference_region_residual);
}

bool Tracker::TextureDisowns(const SolveSummary& s) const {
  const double ratio = options_.failure.recover_share_ratio;
  if (ratio <= 0.0 || share_reference_ <= 0.0 || !PhotometricJudges()) return false;
  if (s.share >= ratio * share_reference_) return false;
  UNSEEN_LOG_DEBUG("tracker: a re-acquired pose's texture agrees on {:.2f} of its pixels against "
                   "{:.2f} while tracked: still lost",
                   s.share, share_reference_);
  return true;
}

bool Tracker::LightChanged(const SolveSummary& s, bool has_depth) const {
  const PhotometricOptions& po = options_.photometric;
  const RegionModalityOptions& ro = options_.region;
  // Measured depth anchors the pose whatever the light does; colours from the frames
  // follow the light already.
  if (po.light_change_fit <= 0.0 || has_depth || !PhotometricJudges() || !ro.enabled ||
      model_ != given_model_) {
    return false;
  }
  const FailureOptions& f = options_.failure;
  if (s.region_counts.used < f.min_region_lines || s.region_counts.Agreement() < ro.good_agreement ||
      RegionResidualRatio(s) > f.good_region_residual_ratio) {
    return false;  // the silhouette does not vouch for the pose
  }
  return PhotometricFit(s) < po.light_change_fit &&
         s.counts.RejectionGathering() < po.light_change_max_gathering;
}

bool Tracker::TextureDragsSilhouette(const SolveSummary& s, bool has_depth) const {
  const PhotometricOptions& po = options_.photometric;
  // Measured depth anchors the pose; without occlusion rejection a silhouette off its
  // contour is as likely an occluder's doing (the texture's pixels on it are not rejected).
  if (po.silhouette_drag_ratio <= 0.0 || has_depth || !PhotometricJudges() ||
      !options_.region.enabled || !options_.selection.use_occlusion_rejection ||
      model_ != given_model_ || region_residual_reference_ <= 0.0 ||
      s.region_counts.used < options_.failure.min_region_lines) {
    return false;
  }
  // A texture that vouches for the pose on most of its pixels is not dragged; pixels
  // rejected in blocks rather than over the object are an occluder's (as LightChanged).
  return RegionResidualRatio(s) > po.silhouette_drag_ratio &&
         s.share < po.silhouette_drag_max_share &&
         s.counts.RejectionGathering() < po.light_change_max_gathering;
}

TrackResult Tracker::AlignFirstFrame(const Frame& frame, const Rigid3d& given) {
  const Learnt given_learnt = SaveLearnt();
  const bool joint = use_photometric_ && options_.region.enabled;
  TrackResult r = AlignFirstFrameAt(frame, given);
  if (!joint || !use_photometric_ || !options_.photometric.start_by_silhouette ||
      r.confidence >= options_.failure.recover_confidence) {
    return r;
  }
  // The first frame did not confirm the given pose: it may be further off than the
  // colours' basin (a pose from another tracker, a rough calibration). The silhouette's
  // basin is wider: it aligns the frame first, and the joint alignment (with the colours'
  // weight the checks above settled) starts from there; the more confident result is kept.
  const Learnt first_learnt = SaveLearnt();
  RestoreLearnt(given_learnt);
  use_photometric_ = false;
  const TrackResult by_silhouette = AlignPredicted(frame, given);
  use_photometric_ = true;
  TrackResult again = AlignPredicted(frame, by_silhouette.world_from_obj);
  again.summary.times += by_silhouette.summary.times;
  again.summary.times += r.summary.times;
  if (again.confidence > r.confidence) {
    UNSEEN_LOG_INFO("tracker: the first frame aligned from the given pose reached confidence "
                    "{:.2f}; aligned by the silhouette first, {:.2f}",
                    r.confidence, again.confidence);
    return again;
  }
  r.summary.times = again.summary.times;
  RestoreLearnt(first_learnt);
  return r;
}

TrackResult Tracker::AlignFirstFrameAt(const Frame& frame, const Rigid3d& given) {
  const Learnt given_learnt = SaveLearnt();
  TrackResult r = AlignPredicted(frame, given);
  const LiveAppearanceOptions& lo = options_.live_appearance;
  // Lines left out because they run on past their end do not count against the pose: many
  // of them mean the rest confirm it on too little of the object.
  const bool overruns = options_.region.skip_overrun_lines &&
                        r.summary.region_counts.OverrunShare() > lo.first_overrun_share;
  if (!live_appearance_ && lo.when_silhouette_fails && MayTakeLiveAppearance() &&
      (r.confidence < lo.min_confidence || overruns)) {
    // The silhouette alone does not confirm the given pose (an object coloured like its
    // surroundings): the object as the first frame shows it there may.
    const Learnt silhouette_learnt = SaveLearnt();
    RestoreLearnt(given_learnt);
    if (TakeLiveAppearance(frame, given)) {
      live_appearance_ = true;
      TrackResult with_colours = AlignPredicted(frame, given);
      with_colours.summary.times += r.summary.times;
      if (with_colours.confidence > r.confidence ||
          (overruns && with_colours.confidence >= r.confidence &&
           with_colours.confidence >= lo.min_confidence)) {
        UNSEEN_LOG_INFO(
            "tracker: the silhouette alone does not confirm the given pose "
            "(confidence {:.2f}, {:.0f} % of its lines run on past their end); "
            "the model takes its colours from the frames (confidence {:.2f})",
            r.confidence, 100.0 * std::max(0.0, r.summary.region_counts.OverrunShare()),
            with_colours.confidence);
        return with_colours;
      }
      StartWithGivenModel();  // back to the model's own (no) colours
      start_colours_lost_ =
          true;  // nor does a print give them at this frame (PrintSeenAtFirstFrame)
      r.summary.times = with_colours.summary.times;
    }
    RestoreLearnt(silhouette_learnt);
    return r;
  }
  const RegionModalityOptions& ro = options_.region;
  const PhotometricOptions& po = options_.photometric;
  if (!use_photometric_ || !ro.enabled) return r;
  const StageTimes joint_times = r.summary.times;
  if (PhotometricFit(r.summary) < po.min_start_fit &&
      r.summary.start_region_counts.EdgeShare() >= ro.min_start_edge_share) {
    // At the pose it was given, the image has an edge along most of the silhouette (the
    // object is there) but the model's appearance does not fit it (wrong colours,
    // highlights the model lacks): the optical flow would drag the pose away. The
    // silhouette tracks it instead.
    UNSEEN_LOG_INFO("tracker: the model's appearance does not fit the first frame (fit {:.2f} "
                    "< {:.2f}); tracking by its silhouette",
                    PhotometricFit(r.summary), po.min_start_fit);
    use_photometric_ = false;
    live_appearance_ = options_.live_appearance.enabled;
    r = AlignPredicted(frame, given);
    r.summary.times += joint_times;
    return r;
  }
  if (po.start_drag_px <= 0.0) return r;
  // The given pose is taken to be close. Where the model's colours are shaded unlike the
  // image (another renderer, a real camera), the composed virtual image fits best with a
  // smaller model (the input shows wherever the model does not), so the photometric term
  // drags the object away, typically deeper; the silhouette alone does not.
  // What the joint alignment left for the next frames (its correction, the colour samples
  // it learnt) is kept unless the silhouette's result replaces it.
  const Learnt joint_learnt = SaveLearnt();
  use_photometric_ = false;
  TrackResult by_silhouette = AlignPredicted(frame, given);
  use_photometric_ = true;
  const double joint_px = r.summary.correction_px;
  const double silhouette_px = by_silhouette.summary.correction_px;
  if (joint_px > po.start_drag_px && joint_px > po.start_drag_ratio * silhouette_px &&
      by_silhouette.confidence > 0.0) {
    const StageTimes silhouette_times = by_silhouette.summary.times;
    if (po.dragged_weight <= 0.0) {
      UNSEEN_LOG_INFO("tracker: the model's appearance drags the first frame's pose {:.1f} px "
                      "(the silhouette alone {:.1f} px); tracking by its silhouette",
                      joint_px, silhouette_px);
      use_photometric_ = false;
      live_appearance_ = options_.live_appearance.enabled;
      by_silhouette.summary.times += joint_times;
      return by_silhouette;
    }
    // Demoted, not dropped: the silhouette leads, the colours settle what it leaves open.
    UNSEEN_LOG_INFO("tracker: the model's appearance drags the first frame's pose {:.1f} px "
                    "(the silhouette alone {:.1f} px); the silhouette leads",
                    joint_px, silhouette_px);
    photometric_demoted_ = true;
    dragged_at_start_ = true;
    TrackResult demoted = AlignPredicted(frame, given);
    demoted.summary.times += joint_times;
    demoted.summary.times += silhouette_times;
    return demoted;
  }
  RestoreLearnt(joint_learnt);
  r.summary.times += by_silhouette.summary.times;
  return r;
}

}  // namespace unseen
