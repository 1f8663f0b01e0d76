// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Which appearance the tracker renders and how much it trusts it: the model's own colours
// (the photometric modality in use, demoted or not), or colours taken from the confidently
// tracked frames by projective texturing (LiveAppearanceOptions), and the switch to those
// when the model's own colours never fitted the images.
#include "unseen/track/tracker.h"

#include <algorithm>

#include "unseen/track/live_appearance.h"
#include "unseen/util/logging.h"

namespace unseen {

void Tracker::StartWithGivenModel() {
  const PhotometricOptions& po = options_.photometric;
  const bool has_appearance = given_model_->HasAppearance();
  use_photometric_ = po.enabled && (!po.require_appearance || has_appearance ||
                                    !options_.region.enabled);
  // A model without colours takes them from the frames the silhouette tracks (or every
  // model, LiveAppearanceOptions::always).
  const LiveAppearanceOptions& lo = options_.live_appearance;
  live_appearance_ = po.enabled && lo.enabled && options_.region.enabled &&
                     (!has_appearance || lo.always);
  frames_since_capture_ = 0;
  best_live_share_ = 0.0;
  latest_live_.reset();
  photometric_demoted_ = false;
  dragged_at_start_ = false;
  demoted_by_light_ = false;
  start_colours_lost_ = false;
  best_share_ = 0.0;
  poor_fit_frames_ = 0;
  model_ = given_model_;
}

bool Tracker::ColoursNeverFitted(const TrackResult& r) {
  const LiveAppearanceOptions& lo = options_.live_appearance;
  if (lo.poor_fit_frames <= 0 || live_appearance_ || !use_photometric_ || dragged_at_start_ ||
      (demoted_by_light_ && !lo.replace_after_light_change) || !options_.region.enabled ||
      model_ != given_model_) {
    return false;
  }
  if (r.status != TrackStatus::kTracking || r.confidence < lo.poor_fit_confidence ||
      r.summary.search_candidates > 0) {
    return false;
  }
  const double share = r.summary.share;
  best_share_ = std::max(best_share_, share);
  if (share >= lo.poor_fit_share) {
    poor_fit_frames_ = 0;
  } else if (r.summary.counts.RejectionGathering() <
             options_.photometric.light_change_max_gathering) {
    ++poor_fit_frames_;  // spread over the object: the colours, not an occluder
  }
  return poor_fit_frames_ >= lo.poor_fit_frames && best_share_ < lo.poor_fit_best_share;
}

bool Tracker::MayTakeLiveAppearance() const {
  return options_.photometric.enabled && options_.region.enabled &&
         !given_model_->HasAppearance();
}

bool Tracker::BelowHeldShare(double share) const {
  return share < options_.live_appearance.refresh_share_ratio * best_live_share_;
}

bool Tracker::HeldAppearanceFaded(const TrackResult& r) const {
  return live_appearance_ && model_ != given_model_ && latest_live_ && latest_live_ != model_ &&
         (BelowHeldShare(r.summary.share) ||
          r.confidence < options_.reacquisition.doubtful_confidence);
}

void Tracker::UpdateLiveAppearance(const Frame& frame, const TrackResult& r) {
  const LiveAppearanceOptions& lo = options_.live_appearance;
  if (!live_appearance_ || r.status != TrackStatus::kTracking || r.confidence < lo.min_confidence) {
    return;
  }
  if (model_ == given_model_ || lo.refresh_frames <= 1) {
    TakeLiveAppearance(frame, r.world_from_obj);
    return;
  }
  // A texture held over frames: the latest one is kept aside for a frame it no longer fits.
  best_live_share_ = std::max(best_live_share_, r.summary.share);
  latest_live_ = CaptureLiveAppearance(frame, r.world_from_obj);
  const bool faded = BelowHeldShare(r.summary.share);
  if ((++frames_since_capture_ >= lo.refresh_frames || faded) && latest_live_) {
    AdoptLiveAppearance(latest_live_);
  }
}

std::shared_ptr<const Mesh> Tracker::PrintSeenAtFirstFrame(const Frame& frame,
                                                           const TrackResult& r) const {
  const LiveAppearanceOptions& lo = options_.live_appearance;
  if (live_appearance_ || start_colours_lost_ || lo.print_share > 1.0 || !MayTakeLiveAppearance() ||
      model_ != given_model_ || r.status != TrackStatus::kTracking ||
      r.confidence < lo.min_confidence) {
    return nullptr;
  }
  std::shared_ptr<const Mesh> seen = CaptureLiveAppearance(frame, r.world_from_obj);
  if (!seen) return nullptr;
  double share = -1.0;
  for (const Projector& p : seen->projectors) {
    share = std::max(share, TexturedShare(p, lo.print_min_gradient, lo.print_inset_px));
  }
  if (share < lo.print_share) return nullptr;
  UNSEEN_LOG_INFO(
      "tracker: the model has no colours but the first frame shows a print on {:.0f} % "
      "of it; it takes its colours from the tracked frames",
      100.0 * share);
  return seen;
}

std::shared_ptr<const Mesh> Tracker::CaptureLiveAppearance(const Frame& frame,
                                                           const Rigid3d& world_from_obj) const {
  const LiveAppearanceOptions& lo = options_.live_appearance;
  auto live = std::make_shared<Mesh>(*given_model_);
  live->projectors.clear();
  const float tolerance_m = static_cast<float>(lo.occlusion_tolerance * sphere_radius_);
  for (int c = 0; c < rig_.size(); ++c) {
    if (frame.images[c].empty()) continue;
    const PinholeCamera& camera = rig_.cameras[c].intrinsics;
    const Rigid3d cam_from_obj = cam_from_world_[c] * world_from_obj;
    const std::optional<PixelRect> rect = ObjectRect(camera, cam_from_obj);
    if (!rect) continue;
    std::optional<Projector> p = CaptureProjector(*given_model_, camera, cam_from_obj,
                                                  frame.images[c], rect->Grow(lo.margin_px),
                                                  tolerance_m);
    if (p) live->projectors.push_back(std::move(*p));
  }
  if (live->projectors.empty()) return nullptr;
  return live;
}

bool Tracker::TakeLiveAppearance(const Frame& frame, const Rigid3d& world_from_obj) {
  std::shared_ptr<const Mesh> live = CaptureLiveAppearance(frame, world_from_obj);
  if (!live) return false;
  AdoptLiveAppearance(std::move(live));
  return true;
}

void Tracker::AdoptLiveAppearance(std::shared_ptr<const Mesh> live) {
  if (model_ == given_model_) {
    UNSEEN_LOG_DEBUG("tracker: the model takes its colours from the tracked frames");
    residual_reference_px_ = 0.0;  // the fit to the given colours says nothing of these
    share_reference_ = 0.0;
  }
  model_ = std::move(live);
  use_photometric_ = true;
  photometric_demoted_ = false;  // colours from the frames have a weight of their own
  frames_since_capture_ = 0;
  best_live_share_ = 0.0;
}

}  // namespace unseen
