// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/model_updater.h"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "unseen/model/test_rig_scene.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

using testing::MakeRigScene;
using testing::RigScene;

class ModelUpdates : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = MakeRigScene();
    options_.depth.source = DepthSourceKind::kSensor;
    options_.align_to_current = true;  // exercised here: exact depth
    modeller_ = std::make_unique<Modeller>(scene_.rig, 0, options_);
    const ModelBuild first = modeller_->Build(scene_.frame, scene_.world_from_obj, PixelRect());
    ASSERT_TRUE(first.ok()) << first.why;
    model_ = *first.mesh;
    update_.mode = ModelUpdateMode::kPeriodic;  // the thesis's (incremental: its own test)
    update_.every_frames = 3;
    update_.asynchronous = false;
  }
  RigScene scene_;
  ModellerOptions options_;
  std::unique_ptr<Modeller> modeller_;
  Mesh model_;  // the model in use
  ModelUpdateOptions update_;
};

TEST_F(ModelUpdates, EveryNthConfidentFrameGivesANewModel) {
  ModelUpdater updater(modeller_.get(), update_);
  EXPECT_FALSE(updater.AfterFrame(scene_.frame, scene_.world_from_obj, 1.0, model_));
  EXPECT_FALSE(updater.AfterFrame(scene_.frame, scene_.world_from_obj, 1.0, model_));
  // Due, but doubtful: waits for a confident frame.
  EXPECT_FALSE(updater.AfterFrame(scene_.frame, scene_.world_from_obj, 0.3, model_));
  const std::optional<Mesh> model =
      updater.AfterFrame(scene_.frame, scene_.world_from_obj, 0.9, model_);
  ASSERT_TRUE(model.has_value());
  EXPECT_GT(model->num_triangles(), 30);
  EXPECT_EQ(updater.stats().built, 1);
  // Built at the true pose on exact depth: aligned to the model in use, moved by no more
  // than the model's chords are off the surface.
  EXPECT_EQ(updater.stats().aligned, 1);
  EXPECT_LT(updater.stats().correction_mm, 2.0);
  EXPECT_FALSE(updater.AfterFrame(scene_.frame, scene_.world_from_obj, 1.0, model_));
}

TEST_F(ModelUpdates, AFallingConfidenceBringsTheNextBuildForward) {
  update_.every_frames = 30;
  update_.refresh_frames = 5;
  update_.refresh_confidence = 0.9;
  ModelUpdater updater(modeller_.get(), update_);
  // Confident frames, then one less so but too soon after the model.
  for (double confidence : {1.0, 1.0, 0.85, 1.0}) {
    EXPECT_FALSE(updater.AfterFrame(scene_.frame, scene_.world_from_obj, confidence, model_));
  }
  // Too doubtful to model, then 0.85 after five frames: the model is refreshed now.
  EXPECT_FALSE(updater.AfterFrame(scene_.frame, scene_.world_from_obj, 0.5, model_));
  EXPECT_TRUE(updater.AfterFrame(scene_.frame, scene_.world_from_obj, 0.85, model_).has_value());
  EXPECT_EQ(updater.stats().started, 1);

  // A confidence that falls through the window in one frame (1.0, then 0.7 < min_confidence
  // 0.8) still refreshes the model when it is at least refresh_fall_confidence; one that
  // was already inside the window, or falls below that, does not.
  ASSERT_LT(update_.refresh_fall_confidence, 0.7);
  ASSERT_GT(update_.refresh_fall_confidence, 0.5);
  ModelUpdater falling(modeller_.get(), update_);
  for (double confidence : {1.0, 1.0, 1.0, 1.0}) {
    EXPECT_FALSE(falling.AfterFrame(scene_.frame, scene_.world_from_obj, confidence, model_));
  }
  EXPECT_TRUE(falling.AfterFrame(scene_.frame, scene_.world_from_obj, 0.7, model_).has_value());
  ModelUpdater within(modeller_.get(), update_);
  for (double confidence : {1.0, 1.0, 1.0, 0.85}) {  // 0.85: too soon after the model
    EXPECT_FALSE(within.AfterFrame(scene_.frame, scene_.world_from_obj, confidence, model_));
  }
  EXPECT_FALSE(within.AfterFrame(scene_.frame, scene_.world_from_obj, 0.7, model_));
  update_.refresh_fall_confidence = update_.min_confidence;  // off
  ModelUpdater no_fall(modeller_.get(), update_);
  for (double confidence : {1.0, 1.0, 1.0, 1.0}) {
    EXPECT_FALSE(no_fall.AfterFrame(scene_.frame, scene_.world_from_obj, confidence, model_));
  }
  EXPECT_FALSE(no_fall.AfterFrame(scene_.frame, scene_.world_from_obj, 0.7, model_));

  // Without the refresh, only every_frames.
  update_.refresh_confidence = 0.0;
  ModelUpdater every_30(modeller_.get(), update_);
  for (int i = 0; i < 29; ++i) {
    EXPECT_FALSE(every_30.AfterFrame(scene_.frame, scene_.world_from_obj, 0.85, model_));
  }
  EXPECT_TRUE(every_30.AfterFrame(scene_.frame, scene_.world_from_obj, 0.85, model_).has_value());
}

TEST_F(ModelUpdates, AFrameThatCannotBeModelledKeepsTheModelInUse) {
  ModelUpdater updater(modeller_.get(), update_);
  Frame no_depth = scene_.frame;
  no_depth.depths[0] = cv::Mat(scene_.frame.depths[0].size(), CV_32FC1, cv::Scalar(0));
  for (int i = 0; i < 3; ++i)
    EXPECT_FALSE(updater.AfterFrame(no_depth, scene_.world_from_obj, 1.0, model_));
  EXPECT_EQ(updater.stats().started, 1);
  EXPECT_EQ(updater.stats().failed, 1);
  EXPECT_FALSE(updater.stats().last_failure.empty());
}

TEST_F(ModelUpdates, BuildsBesideTheTrackingAndHandsOverLater) {
  update_.asynchronous = true;
  update_.every_frames = 1;
  ModelUpdater updater(modeller_.get(), update_);
  EXPECT_FALSE(updater.AfterFrame(scene_.frame, scene_.world_from_obj, 1.0, model_));  // started
  std::optional<Mesh> model;
  for (int i = 0; i < 200 && !model; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    model = updater.AfterFrame(scene_.frame, scene_.world_from_obj, 1.0, model_);
  }
  ASSERT_TRUE(model.has_value());
  EXPECT_EQ(updater.stats().started, 1);
}

TEST_F(ModelUpdates, IncrementalFusesEveryBuildIntoOneModel) {
  update_.mode = ModelUpdateMode::kIncremental;
  ModelUpdater updater(modeller_.get(), update_);
  ModelBuild first = modeller_->Build(scene_.frame, scene_.world_from_obj, PixelRect());
  const Mesh start = updater.Start(first);
  EXPECT_EQ(updater.stats().fusion.fused, 1);
  EXPECT_EQ(start.projectors.size(), 1u);
  EXPECT_GT(start.num_triangles(), 100);
  std::optional<Mesh> model;
  for (int i = 0; i < 3 && !model; ++i) {
    model = updater.AfterFrame(scene_.frame, scene_.world_from_obj, 1.0, start);
  }
  ASSERT_TRUE(model.has_value());
  EXPECT_EQ(updater.stats().fusion.fused, 2);
  // The same view again: no new key view, and by default no latest view either.
  EXPECT_EQ(updater.stats().fusion.key_views, 1);
  EXPECT_EQ(model->projectors.size(), 1u);
  EXPECT_LE(model->num_triangles(), options_.fusion.max_triangles);
  EXPECT_EQ(ParseModelUpdateMode("incremental"), ModelUpdateMode::kIncremental);
  // A failed first build cannot start a model.
  EXPECT_THROW(updater.Start(ModelBuild()), Error);
}

TEST_F(ModelUpdates, LatestViewTexturesTheModelWhenAsked) {
  options_.fusion.latest_view = true;
  Modeller modeller(scene_.rig, 0, options_);
  update_.mode = ModelUpdateMode::kIncremental;
  ModelUpdater updater(&modeller, update_);
  const Mesh start =
      updater.Start(modeller.Build(scene_.frame, scene_.world_from_obj, PixelRect()));
  EXPECT_EQ(start.projectors.size(), 1u);  // the first view is a key view, not a latest one
  std::optional<Mesh> model;
  for (int i = 0; i < 3 && !model; ++i) {
    model = updater.AfterFrame(scene_.frame, scene_.world_from_obj, 1.0, start);
  }
  ASSERT_TRUE(model.has_value());
  // The same view again: no new key view, but the latest view textures it too.
  EXPECT_EQ(updater.stats().fusion.key_views, 1);
  EXPECT_EQ(model->projectors.size(), 2u);
}

TEST_F(ModelUpdates, NoneNeverRebuildsAndBadOptionsAreErrors) {
  update_.mode = ModelUpdateMode::kNone;
  ModelUpdater updater(modeller_.get(), update_);
  for (int i = 0; i < 10; ++i)
    EXPECT_FALSE(updater.AfterFrame(scene_.frame, scene_.world_from_obj, 1.0, model_));
  EXPECT_EQ(updater.stats().started, 0);
  EXPECT_THROW(ParseModelUpdateMode("incrementally"), Error);
  update_.every_frames = 0;
  EXPECT_THROW(update_.Check(), Error);
  update_.every_frames = 3;
  update_.refresh_confidence = 1.5;
  EXPECT_THROW(update_.Check(), Error);
  update_.refresh_confidence = 0.9;
  update_.refresh_frames = 0;
  EXPECT_THROW(update_.Check(), Error);
  update_.refresh_frames = 5;
  update_.refresh_fall_confidence = -0.1;
  EXPECT_THROW(update_.Check(), Error);
}

}  // namespace
}  // namespace unseen
