// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The complete system (SPEC 6, thesis 5.1): frame by frame, the interest filter bank and
// the motion segmentation run on the reference camera (the background model learns every
// frame); until an object is tracked, the region selection looks for the object of
// interest; a selected region gives a pose — a known model's by its views
// (select/known_model_pose.h), an unknown object's frame by SPEC 4.4 and its first model
// built there (model/modeller.h) — and the tracker follows it, the model kept current
// beside the tracking (model/model_updater.h). When the track has been lost for a while
// the object is searched for again. Every frame's outcome is a status, never an error:
// learning the background, no object of interest yet, tracking, lost.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "unseen/camera/camera.h"
#include "unseen/io/sequence.h"
#include "unseen/mesh/mesh.h"
#include "unseen/model/model_updater.h"
#include "unseen/model/modeller.h"
#include "unseen/select/interest_filter_bank.h"
#include "unseen/select/known_model_pose.h"
#include "unseen/select/motion_segmentation.h"
#include "unseen/select/region_selection.h"
#include "unseen/track/tracker.h"

namespace unseen {

enum class SystemStatus {
  kLearning,  // the interest filters are still learning (the background model)
  kNoObject,  // no object of interest this frame (or none that could be placed)
  kTracking,
  kLost,  // the tracker lost the object; it searches, then the selection takes over
};
const char* ToString(SystemStatus status);  // "learning", "no object", "tracking", "lost"

// Where the candidate regions come from.
enum class RegionSource {
  kMotion,    // block-based motion segmentation (a moving object before a still camera)
  kInterest,  // the interest map's connected parts (e.g. a position filter: a still object)
};

struct SystemOptions {
  SystemOptions();  // the selection's thresholds for regions of motion (below)
  RegionSource regions = RegionSource::kMotion;
  MotionSegmentationOptions segmentation;
  // Motion regions hold the whole object while the background model flags mostly its
  // edges: the constructor lowers the share and mean of interest to 0.05 and ranks by
  // total interest.
  RegionSelectionOptions selection;
  KnownModelPoseOptions known_pose;
  ModelUpdateOptions update;
  // The object is searched for again after this many frames lost in a row.
  int reselect_after_lost_frames = 10;
  // An unknown object's model rebuilds are selected by the pixels that move with the
  // tracked object (SPEC 5.5; select/interest_filter.h's TrackedMotionFilter, above
  // rebuild_min_interest; MaskRole::kSelects), where it moves enough in the image to tell.
  bool rebuild_from_tracked_motion = true;
  // An unknown object's first model takes the selected region's pixels (the region's label)
  // with measured depth: an interest map's part bounds the object (the table beside the
  // real RGB-D cube lies at its depth; without it 100 -> 92 %), moving blocks select its
  // surface (MaskRole::kSelects: they lie along its outline, on both sides). With depth
  // from the images (stereo, plane sweep) the whole region is modelled by default and the
  // depth's own segmentation finds the object: a slowly moving object moves in few of its
  // blocks and its model was a fragment (held-out three-camera teapot 50 -> 82 %,
  // untextured rock 2.5 -> 30 %, banded goblet 17.5 -> 25 %).
  bool first_model_from_motion_with_image_depth = false;
  TrackedMotionFilterOptions tracked_motion;
  double rebuild_min_interest = 0.3;
  void Check() const;
};

// One frame's outcome.
struct SystemStep {
  int frame_id = 0;
  SystemStatus status = SystemStatus::kLearning;
  std::optional<TrackResult> track;  // the tracker's result, when it ran this frame
  PixelRect region;                  // the selected region, when one was (reference image)
  std::vector<PixelRect> candidates;  // boxes of the candidate regions, when selection ran
  cv::Mat interest;                  // the reference camera's interest map (CV_32FC1)
  std::string note;                  // what happened, for the log ("found ...", "model ...")
};

class System {
 public:
  // `model`: the object's model (metres), or std::nullopt to model it on-line with
  // `modeller_options` (which need a depth source the rig can serve). `reference`: the
  // camera the object is selected (and modelled) in. Throws unseen::Error for invalid
  // options, rig or model.
  System(const Rig& rig, int reference, std::optional<Mesh> model, InterestFilterBank bank,
         const SystemOptions& options = {}, const TrackerOptions& tracker_options = {},
         const ModellerOptions& modeller_options = {});
  ~System();

  // Processes one frame (Frame::images one per rig camera; depths optional). Never
  // throws for what the scene does (no object, object gone); throws unseen::Error for a
  // frame of the wrong shape.
  SystemStep Step(const Frame& frame);

  // The tracker while one exists (it is replaced when an unknown object is modelled anew).
  const Tracker* tracker() const { return tracker_.get(); }
  const ModelUpdater* updater() const { return updater_.get(); }
  bool tracking() const { return active_; }

 private:
  // The pixels of the reference image moving with the tracked object (CV_8UC1), or empty
  // when that cannot be told this frame or `judge` is false (no model build needs them).
  // Called on every tracked frame (the filter keeps the previous image).
  cv::Mat MovingWithObject(const Frame& frame, const TrackResult& track, bool judge);
  // Looks for the object in the selected region; true when tracking starts.
  bool Start(const Frame& frame, const RegionCandidate& region, const cv::Mat& labels,
             SystemStep* step);

  Rig rig_;
  int reference_;
  bool known_model_;
  InterestFilterBank bank_;
  SystemOptions options_;
  TrackerOptions tracker_options_;
  MotionSegmenter segmenter_;
  std::unique_ptr<Tracker> tracker_;
  std::unique_ptr<KnownModelPoser> poser_;
  std::unique_ptr<Modeller> modeller_;
  std::unique_ptr<ModelUpdater> updater_;
  bool active_ = false;
  int lost_frames_ = 0;
  TrackedMotionFilter tracked_motion_;
  std::optional<Rigid3d> previous_tracked_;  // world_from_obj of the previous frame, if tracked
};

}  // namespace unseen
