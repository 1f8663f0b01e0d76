// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The tracking state over frames: the pyramid depth the recent corrections call for, the
// prediction, the status (tracking, lost), coasting and the search while lost, dropped
// frames. The alignment of one frame is tracker.cc's.
#include <algorithm>
#include <cmath>
#include <utility>

#include "unseen/track/reacquisition.h"
#include "unseen/track/tracker.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/timer.h"

namespace unseen {

TrackResult Tracker::AlignPredicted(const Frame& frame, const Rigid3d& predicted) {
  const PyramidOptions& po = options_.pyramid;
  const double trust = options_.reacquisition.doubtful_confidence;
  const int full = NumLevelsFor(predicted);
  int levels = full;
  if (po.adaptive_levels && status_ == TrackStatus::kTracking) {
    // Each coarser level doubles the capture range (3.3).
    const double expected_px = po.prediction_margin * recent_correction_px_;
    levels = std::min(full, po.min_adaptive_levels);
    while (levels < full && expected_px > po.capture_px * double(1 << (levels - 1))) ++levels;
  }
  TrackResult r = AlignChecked(frame, predicted, levels, /*tracking=*/true);
  // A second alignment replaces r when it is more confident (`or_equal`: also when as
  // confident); both were paid for.
  auto keep_better = [&r](TrackResult other, bool or_equal) {
    StageTimes both = r.summary.times;
    both += other.summary.times;
    if (other.confidence > r.confidence || (or_equal && other.confidence == r.confidence)) {
      r = std::move(other);
    }
    r.summary.times = both;
  };
  const double reach_px = po.capture_px * double(1 << (levels - 1));
  if (levels < full && (r.confidence < trust || r.summary.correction_px > 0.75 * reach_px)) {
    keep_better(AlignChecked(frame, predicted, full, /*tracking=*/true), /*or_equal=*/true);
  }
  if (r.confidence < trust && options_.depth.retry_doubtful_with_coarse_depth &&
      CoarseLevelsWithoutDepth(frame)) {
    // A doubtful frame whose coarse levels followed the texture alone: aligned again with
    // the depth rows at every level.
    keep_better(AlignChecked(frame, predicted, levels, /*tracking=*/true, /*coarse_depth=*/true),
                /*or_equal=*/false);
  }
  if (r.confidence >= trust) {
    const double decayed = std::isfinite(recent_correction_px_)
                               ? po.correction_decay * recent_correction_px_
                               : 0.0;
    recent_correction_px_ = std::max(r.summary.correction_px, decayed);
  } else {
    recent_correction_px_ = std::numeric_limits<double>::infinity();
  }
  return r;
}

TrackResult Tracker::Track(const std::vector<cv::Mat>& images_per_camera) {
  Frame frame;
  frame.images = images_per_camera;
  return Track(frame);
}

TrackResult Tracker::Track(const Frame& input_frame) {
  UNSEEN_CHECK(initialized_, "Tracker::Track called before Initialize()");
  Timer total;
  const Frame frame = CheckFrame(input_frame);
  if (std::all_of(frame.images.begin(), frame.images.end(),
                  [](const cv::Mat& im) { return im.empty(); })) {
    return SkipFrame();
  }
  const FailureOptions& f = options_.failure;

  Timer timer;
  const Rigid3d predicted = status_ == TrackStatus::kLost
                                ? Coast()
                                : predictor_->Predict(options_.frame_interval_s);
  const double predict_ms = timer.ElapsedMilliseconds();

  const bool search = status_ == TrackStatus::kLost && f.search_when_lost;
  TrackResult r;
  // The frame aligned again from the prediction (the appearance changed); both paid for.
  auto align_again = [&] {
    const StageTimes first_times = r.summary.times;
    r = AlignPredicted(frame, predicted);
    r.summary.times += first_times;
  };
  if (search) {
    // Re-acquisition (3.9): the coasted pose, correlation seeds, translations and rotations
    // around the last good pose, scored at the coarse levels, the best refined.
    r = Reacquirer().Search(frame, last_good_, predicted);
  } else {
    r = learn_from_start_ ? AlignFirstFrame(frame, predicted) : AlignPredicted(frame, predicted);
  }
  if (!search && !learn_from_start_ && status_ == TrackStatus::kTracking &&
      LightChanged(r.summary, !frame.depths.empty())) {
    // The model's shading no longer matches the image: the silhouette leads from now on.
    UNSEEN_LOG_INFO("tracker: frame {}: the light changed under the model's colours "
                    "(photometric fit {:.2f}, rejections gathered {:.2f}); the silhouette leads",
                    frame.frame_id, PhotometricFit(r.summary),
                    r.summary.counts.RejectionGathering());
    photometric_demoted_ = true;
    demoted_by_light_ = true;
    align_again();
  }
  if (!search && !learn_from_start_ && status_ == TrackStatus::kTracking &&
      r.confidence >= f.lost_confidence &&
      TextureDragsSilhouette(r.summary, !frame.depths.empty())) {
    // The texture pulled the pose off the silhouette's contour (a dim, noisy object whose
    // blurred outline the composed virtual image misreads): the frame aligned again with
    // the silhouette leading is kept, and the silhouette leads from now on, when it is
    // judged as confident and sits that much closer to its contour, as close as its
    // confident frames do (a silhouette misled itself, by a moving lamp, does not take the
    // lead).
    const Learnt joint_learnt = SaveLearnt();
    const TrackResult joint = r;
    photometric_demoted_ = true;
    align_again();
    const double joint_ratio = RegionResidualRatio(joint.summary);
    const double led_ratio = RegionResidualRatio(r.summary);
    if (r.confidence >= std::max(joint.confidence, f.recover_confidence) &&
        led_ratio <= options_.photometric.silhouette_drag_led_ratio &&
        led_ratio * options_.photometric.silhouette_drag_ratio <= joint_ratio) {
      UNSEEN_LOG_INFO(
          "tracker: frame {}: the texture drags the pose off the silhouette "
          "(contour residual {:.2f} -> {:.2f} of the confident frames'); the "
          "silhouette leads",
          frame.frame_id, joint_ratio, led_ratio);
    } else {
      photometric_demoted_ = false;
      RestoreLearnt(joint_learnt);
      const StageTimes both_times = r.summary.times;
      r = joint;
      r.summary.times = both_times;
    }
  }
  if (!search && HeldAppearanceFaded(r)) {
    // The held texture no longer fits (the view or the light moved on): the last tracked
    // frame's colours align this one.
    UNSEEN_LOG_DEBUG("tracker: frame {}: the held colours fit {:.2f} of their best {:.2f}; "
                     "aligned again with the last frame's",
                     frame.frame_id, r.summary.share, best_live_share_);
    AdoptLiveAppearance(latest_live_);
    align_again();
  }
  const bool first_frame = learn_from_start_;
  learn_from_start_ = false;
  if (status_ == TrackStatus::kTracking && options_.reacquisition.seed_when_doubtful &&
      r.confidence < options_.reacquisition.doubtful_confidence) {
    // A doubtful frame may have moved beyond the pyramid's capture range: try the
    // correlation seed before judging it. The motion model did not bring the object
    // where the seed found it: it restarts there rather than learning the jump.
    bool from_seed = false;
    r = Reacquirer().Seed(frame, predicted, std::move(r), &from_seed);
    if (from_seed) predictor_->Reset(r.world_from_obj);
  }

  if (r.confidence >= f.lost_confidence) {
    bad_frames_ = 0;
  } else {
    ++bad_frames_;
  }
  if (status_ == TrackStatus::kTracking) {
    if (bad_frames_ >= f.lost_after_frames) {
      BecomeLost(predicted);
    } else if (r.confidence >= f.lost_confidence) {
      if (first_frame) {
        // The given pose was a guess, not where the object was a frame ago: the first
        // frame's correction of it is no motion.
        predictor_->Reset(r.world_from_obj);
      } else {
        predictor_->Correct(r.world_from_obj, r.confidence);  // weighed by the confidence
      }
      last_good_ = r.world_from_obj;
    }
  } else if (r.confidence >= f.recover_confidence && !TextureDisowns(r.summary)) {
    status_ = TrackStatus::kTracking;
    bad_frames_ = 0;
    predictor_->Reset(r.world_from_obj);
    last_good_ = r.world_from_obj;
  }
  if (status_ == TrackStatus::kLost && bad_frames_ > f.area_memory_frames) {
    area_reference_px_ = 0.0;
  }
  // The reference residual follows the confident frames that fit about as well as it, so
  // that a drift into a worse fit does not raise it; it is kept while lost, to judge the
  // re-acquired pose by the same floor.
  const double residual = r.summary.initial_residual_px;
  if (status_ == TrackStatus::kTracking && r.confidence >= f.recover_confidence) {
    if (r.summary.share > 0.0) {
      share_reference_ = share_reference_ > 0.0
                             ? share_reference_ + f.residual_reference_rate *
                                                      (r.summary.share - share_reference_)
                             : r.summary.share;
    }
    // The object's on-screen area follows the confident frames (FailureOptions::
    // min_area_ratio).
    if (r.summary.object_px > 0.0) {
      area_reference_px_ = area_reference_px_ > 0.0
                               ? area_reference_px_ + f.residual_reference_rate *
                                                          (r.summary.object_px - area_reference_px_)
                               : r.summary.object_px;
    }
    // Each residual's reference follows the frames that fit about as well as it.
    auto follow = [&](double value, double good_ratio, double rate, double* reference) {
      if (*reference <= 0.0) {
        *reference = value;
      } else if (value < good_ratio * *reference) {
        *reference += rate * (value - *reference);
      }
    };
    const bool silhouette_used =
        r.summary.region_counts.used >= f.min_region_lines && r.summary.region_residual > 0.0;
    // The silhouette vouches for the pose: the texture's floor is learnt faster
    // (FailureOptions::vouched_reference_rate). Judged before its own reference moves.
    const bool vouched = silhouette_used &&
                         r.summary.region_counts.Agreement() >= options_.region.good_agreement &&
                         RegionResidualRatio(r.summary) <= f.vouched_region_residual_ratio;
    if (silhouette_used) {
      follow(r.summary.region_residual, f.good_region_residual_ratio, f.residual_reference_rate,
             &region_residual_reference_);
    }
    follow(residual, vouched ? f.vouched_follow_ratio : f.good_residual_ratio,
           vouched ? f.vouched_reference_rate : f.residual_reference_rate, &residual_reference_px_);
  }
  // The colour statistics learn from frames tracked with confidence by a plain alignment
  // (a search's result may come from another candidate than the last one aligned).
  const bool teach = status_ == TrackStatus::kTracking && r.confidence >= f.recover_confidence &&
                     r.summary.search_candidates == 0;
  if (teach) {
    region_.Commit(options_.region.learn_rate);
  } else {
    region_.DiscardPending();
  }
  r.status = status_;
  if (status_ == TrackStatus::kLost) {
    r.world_from_obj = last_good_;
  } else if (r.confidence < f.lost_confidence) {
    // A bad frame within the hysteresis (lost_after_frames): its alignment is not to be
    // believed (a frame of noise can drag it anywhere); the motion model's guess is.
    r.world_from_obj = predicted;
  }
  if (!r.world_from_obj.IsValid()) {  // never report NaN
    r.world_from_obj = last_good_;
    r.confidence = 0.0;
  }
  if (ColoursNeverFitted(r)) {
    UNSEEN_LOG_INFO("tracker: frame {}: the model's colours never fitted the images (photometric "
                    "share {:.2f}, at best {:.2f}); it takes them from the tracked frames",
                    frame.frame_id, r.summary.share, best_share_);
    live_appearance_ = true;
  }
  if (std::shared_ptr<const Mesh> printed =
          first_frame ? PrintSeenAtFirstFrame(frame, r) : nullptr) {
    live_appearance_ = true;
    AdoptLiveAppearance(std::move(printed));  // as UpdateLiveAppearance would take it
  } else {
    UpdateLiveAppearance(frame, r);
  }
  r.summary.times.predict_ms = predict_ms;
  r.summary.times.total_ms = total.ElapsedMilliseconds();
  return r;
}

void Tracker::BecomeLost(const Rigid3d& predicted) {
  status_ = TrackStatus::kLost;
  coasted_frames_ = 0;
  coast_ = predicted;
  if (options_.failure.coast_frames == 0) {
    predictor_->Reset(last_good_);
    coast_ = last_good_;
  }
}

Rigid3d Tracker::Coast() {
  if (coasted_frames_ < options_.failure.coast_frames) {
    coast_ = predictor_->Predict(options_.frame_interval_s);
    ++coasted_frames_;
  }
  return coast_;
}

TrackResult Tracker::SkipFrame() {
  UNSEEN_CHECK(initialized_, "Tracker::SkipFrame called before Initialize()");
  Timer total;
  if (status_ == TrackStatus::kTracking) {
    // The object moved on meanwhile.
    const Rigid3d predicted = predictor_->Predict(options_.frame_interval_s);
    if (++bad_frames_ >= options_.failure.lost_after_frames) BecomeLost(predicted);
    // The next frame is a frame interval further from the last correction.
    recent_correction_px_ = std::numeric_limits<double>::infinity();
  } else {
    Coast();
  }
  TrackResult r;
  r.world_from_obj = last_good_;
  r.status = TrackStatus::kLost;
  r.confidence = 0.0;
  r.summary.times.total_ms = total.ElapsedMilliseconds();
  return r;
}

}  // namespace unseen
