// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/model_updater.h"

#include <chrono>
#include <cmath>
#include <utility>

#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/timer.h"

namespace unseen {

std::string ToString(ModelUpdateMode mode) {
  switch (mode) {
    case ModelUpdateMode::kNone:
      return "none";
    case ModelUpdateMode::kPeriodic:
      return "periodic";
    case ModelUpdateMode::kIncremental:
      return "incremental";
  }
  return "?";
}

ModelUpdateMode ParseModelUpdateMode(const std::string& text) {
  for (ModelUpdateMode mode :
       {ModelUpdateMode::kNone, ModelUpdateMode::kPeriodic, ModelUpdateMode::kIncremental}) {
    if (text == ToString(mode)) return mode;
  }
  ThrowError("model update '{}' is not one of none, periodic, incremental", text);
}

void ModelUpdateOptions::Check() const {
  UNSEEN_CHECK(every_frames >= 1, "update.every_frames {} must be >= 1", every_frames);
  UNSEEN_CHECK(refresh_confidence >= 0.0 && refresh_confidence <= 1.0,
               "update.refresh_confidence {} must be in [0, 1]", refresh_confidence);
  UNSEEN_CHECK(refresh_frames >= 1, "update.refresh_frames {} must be >= 1", refresh_frames);
  UNSEEN_CHECK(min_confidence >= 0.0 && min_confidence <= 1.0,
               "update.min_confidence {} must be in [0, 1]", min_confidence);
  UNSEEN_CHECK(refresh_fall_confidence >= 0.0 && refresh_fall_confidence <= 1.0,
               "update.refresh_fall_confidence {} must be in [0, 1]", refresh_fall_confidence);
}

ModelUpdater::ModelUpdater(const Modeller* modeller, const ModelUpdateOptions& options)
    : modeller_(*modeller), options_(options) {
  options_.Check();
  if (options_.mode == ModelUpdateMode::kIncremental) {
    fusion_ = std::make_unique<ModelFusion>(modeller_.rig().cameras[modeller_.reference()],
                                            modeller_.options().segmentation.max_radius_m,
                                            modeller_.options().fusion);
  }
}

ModelUpdater::~ModelUpdater() {
  if (pending_.valid()) pending_.wait();  // the build reads the modeller
}

Mesh ModelUpdater::Start(const ModelBuild& first) {
  UNSEEN_CHECK(first.ok(), "ModelUpdater: the first build failed: {}", first.why);
  if (!fusion_) return *first.mesh;
  std::string why;
  std::optional<Mesh> fused = fusion_->Fuse(first, &why);
  stats_.fusion = fusion_->report();
  if (!fused) {
    UNSEEN_LOG_DEBUG("model update: {}; tracking the first build's mesh", why);
    return *first.mesh;
  }
  return std::move(*fused);
}

ModelBuild ModelUpdater::BuildAndFuse(const Frame& frame, const Rigid3d& world_from_obj,
                                      const Mesh& current, const cv::Mat& mask) {
  ModelBuild build =
      modeller_.Build(frame, world_from_obj, PixelRect(), mask, &current, MaskRole::kSelects);
  if (!build.ok() || !fusion_) return build;
  Timer timer;
  std::string why;
  build.mesh = fusion_->Fuse(build, &why);
  if (!build.mesh) build.why = why;
  build.mesh_ms += timer.ElapsedMilliseconds();
  return build;
}

std::optional<Mesh> ModelUpdater::Collect(ModelBuild build) {
  stats_.build_ms += build.depth_ms + build.mesh_ms;
  if (!build.ok()) {
    ++stats_.failed;
    stats_.last_failure = build.why;
    UNSEEN_LOG_DEBUG("model update: cannot model the frame: {}", build.why);
    return std::nullopt;
  }
  if (fusion_) stats_.fusion = fusion_->report();
  ++stats_.built;
  if (build.alignment.ok) {
    ++stats_.aligned;
    stats_.correction_mm += 1e3 * build.alignment.shift_m;
  }
  ++stats_.swapped;
  frames_since_model_ = 0;
  UNSEEN_LOG_DEBUG("model update: new model, {} triangles, {:.1f} ms", build.mesh->num_triangles(),
                   build.depth_ms + build.mesh_ms);
  return std::move(build.mesh);
}

std::optional<Mesh> ModelUpdater::AfterFrame(const Frame& frame, const Rigid3d& world_from_obj,
                                             double confidence, const Mesh& current,
                                             const cv::Mat& mask) {
  ++frames_since_model_;
  const double previous_confidence = std::exchange(previous_confidence_, confidence);
  std::optional<Mesh> ready;
  if (pending_.valid() && pending_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
    ready = Collect(pending_.get());
  }
  if (options_.mode == ModelUpdateMode::kNone || pending_.valid() || ready) return ready;
  if (!DueAfter(frames_since_model_, confidence, previous_confidence)) return ready;
  ++stats_.started;
  frames_since_model_ = 0;  // the next attempt after every_frames more, built or not
  if (!options_.asynchronous) {
    return Collect(BuildAndFuse(frame, world_from_obj, current, mask));
  }
  // The frame's images are shared, not copied: nothing writes to a frame once read. The
  // model in use is copied (the tracker may swap it meanwhile).
  pending_ = std::async(std::launch::async, [this, frame, world_from_obj, model = current, mask] {
    return BuildAndFuse(frame, world_from_obj, model, mask);
  });
  return ready;
}

bool ModelUpdater::AfterTracked(const Frame& frame, const TrackResult& result, Tracker* tracker,
                                const cv::Mat& mask) {
  if (result.status != TrackStatus::kTracking) {
    previous_confidence_ = 0.0;
    return false;
  }
  std::optional<Mesh> next =
      AfterFrame(frame, result.world_from_obj, result.confidence, tracker->given_model(), mask);
  if (!next) return false;
  tracker->SetModel(std::move(*next));
  return true;
}

}  // namespace unseen
