// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Keeping the on-line model current (SPEC 5.4, thesis 3.4): only the side the cameras see
// can be modelled, so the model must follow the object as it turns. The thesis's periodic
// replacement: every `every_frames` frames, a confidently tracked frame is modelled anew
// at the tracked pose (the object frame carried over, so the pose stream continues), on a
// thread of its own beside the tracking; the new model is handed over at the next frame
// boundary once it is built. Beyond the thesis, incremental modelling (model_fusion.h):
// each build's depth is fused into one model in the first build's object frame, which
// grows with every side seen and does not drift with the tracked pose at each rebuild.
#pragma once

#include <future>
#include <memory>
#include <optional>
#include <string>

#include "unseen/mesh/mesh.h"
#include "unseen/model/model_fusion.h"
#include "unseen/model/modeller.h"
#include "unseen/track/tracker.h"

namespace unseen {

// kIncremental by default: measured better than the thesis's kPeriodic on every
// development and rendered sequence but for the last tenth of the 5-camera cube (README).
enum class ModelUpdateMode { kNone, kPeriodic, kIncremental };

// "none", "periodic", "incremental"; Parse throws unseen::Error naming the value.
std::string ToString(ModelUpdateMode mode);
ModelUpdateMode ParseModelUpdateMode(const std::string& text);

struct ModelUpdateOptions {
  ModelUpdateMode mode = ModelUpdateMode::kIncremental;
  int every_frames = 30;        // frames between model builds (thesis: n = 30)
  double min_confidence = 0.8;  // a frame tracked at least this confidently is modelled
  // A build is due sooner, after refresh_frames, on a frame whose confidence has fallen
  // below refresh_confidence (still at least min_confidence): the model explains the
  // images less well than it did (the object turned a side the model lacks into view, the
  // light moved), and left until every_frames it would lose the object first (a model of
  // one view of a turning truck: confidence 1.0 -> 0.2 in 16 frames at a pose 1-2 mm off).
  // refresh_confidence 0: only every_frames.
  double refresh_confidence = 0.9;
  int refresh_frames = 5;
  // A confidence that falls through the refresh's window in one frame (the frame before at
  // least refresh_confidence, this one below min_confidence) still starts that build when
  // it is at least refresh_fall_confidence: otherwise no build may start while it goes on
  // falling (a truck's 0.93 -> 0.79 -> ... -> 0.2). refresh_fall_confidence >=
  // min_confidence: off.
  double refresh_fall_confidence = 0.6;
  bool asynchronous = true;     // build beside the tracking (false: within the frame)
  void Check() const;
};

struct ModelUpdateStats {
  int started = 0, built = 0, failed = 0, swapped = 0;
  double build_ms = 0.0;       // summed over finished builds
  int aligned = 0;             // builds aligned to the model in use
  double correction_mm = 0.0;  // summed shift of the surface by those alignments
  std::string last_failure;
  FusionReport fusion;  // kIncremental: the fused model's state after the last build
};

class ModelUpdater {
 public:
  // `modeller` must outlive this.
  ModelUpdater(const Modeller* modeller, const ModelUpdateOptions& options);
  ~ModelUpdater();

  // The model to track from the first build (which must have succeeded): its mesh, or
  // with kIncremental the fused model of its depth (the build's mesh when the fused volume
  // holds no surface).
  Mesh Start(const ModelBuild& first);

  // After each tracked frame, with the tracker's pose and confidence for it. Returns a
  // new model to swap in now (Tracker::SetModel) when a build has finished; starts a build
  // of this frame when one is due. A build that cannot model the frame is counted and
  // dropped (the model in use stays).
  // `current`: the model in use (ModellerOptions::align_to_current aligns the new surface
  // to it). `mask` (optional, CV_8UC1 of the reference camera's size): pixels of the
  // object in this frame (those moving with it, select/interest_filter.h's
  // TrackedMotionFilter), handed to Modeller::Build as MaskRole::kSelects.
  std::optional<Mesh> AfterFrame(const Frame& frame, const Rigid3d& world_from_obj,
                                 double confidence, const Mesh& current,
                                 const cv::Mat& mask = cv::Mat());

  // AfterFrame for the frame `tracker` just tracked (`result`), when it tracked it: a model
  // that is ready replaces the tracker's (Tracker::SetModel) at this frame boundary. True
  // when it did.
  bool AfterTracked(const Frame& frame, const TrackResult& result, Tracker* tracker,
                    const cv::Mat& mask = cv::Mat());

  // Whether the next AfterFrame at `confidence` starts a build (none running, enough frames
  // since the last, confident enough): what only a build needs (a mask) is made then only.
  bool BuildsNext(double confidence) const {
    return options_.mode != ModelUpdateMode::kNone && !pending_.valid() &&
           DueAfter(frames_since_model_ + 1, confidence, previous_confidence_);
  }

  const ModelUpdateStats& stats() const { return stats_; }

 private:
  // Whether a frame `frames_since_model` frames after the last build, tracked at
  // `confidence` after one at `previous_confidence`, starts a build.
  bool DueAfter(int frames_since_model, double confidence, double previous_confidence) const {
    const bool refresh = frames_since_model >= options_.refresh_frames &&
                         confidence < options_.refresh_confidence;
    if (confidence < options_.min_confidence) {
      // Fell through the refresh's window in one frame.
      return refresh && previous_confidence >= options_.refresh_confidence &&
             confidence >= options_.refresh_fall_confidence;
    }
    return frames_since_model >= options_.every_frames || refresh;
  }
  std::optional<Mesh> Collect(ModelBuild build);
  // Modeller::Build, then with kIncremental the fusion of its depth (on the build's thread:
  // only one build runs at a time).
  ModelBuild BuildAndFuse(const Frame& frame, const Rigid3d& world_from_obj, const Mesh& current,
                          const cv::Mat& mask);

  const Modeller& modeller_;
  ModelUpdateOptions options_;
  int frames_since_model_ = 0;
  double previous_confidence_ = 0.0;  // of the last frame tracked (0 after a lost one)
  std::unique_ptr<ModelFusion> fusion_;  // kIncremental
  std::future<ModelBuild> pending_;
  ModelUpdateStats stats_;
};

}  // namespace unseen
