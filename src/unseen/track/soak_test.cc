// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// A short soak run (the long one is bench/soak_benchmark): a 40-frame sequence played over
// 300 frames with faults injected often, so that the tracker loses and finds the object
// several times; no NaN pose, no exception.
#include "unseen/track/soak.h"

#include <gtest/gtest.h>

#include <tuple>

#include "unseen/mesh/primitives.h"
#include "unseen/track/test_scene.h"
#include "unseen/util/error.h"
#include "unseen/util/testing.h"

namespace unseen {
namespace {

// A 320x240 camera and the lettered cube passing in front of it, 1.5 mm and 0.4 degrees a
// frame; the models: the cube, the cube with a coarser texture, the cube 1 % larger.
SoakSource SmallSource(int frames) {
  SoakSource source;
  source.rig.cameras.push_back({"cam0", PinholeCamera::Centered(320, 240, 420.0), Rigid3d()});
  const Mesh cube = MakeLetteredCube(0.096, 128);
  const cv::Mat background = testing::Background(source.rig.cameras[0].intrinsics, 5);
  for (int k = 0; k < frames; ++k) {
    const Rigid3d pose(ExpSO3(Eigen::Vector3d(0.45, 0.7 + 0.007 * k, 0.1)),
                       Eigen::Vector3d(-0.03 + 0.0015 * k, 0.01, 0.9));
    cv::Mat image;
    testing::RenderOverBackground(cube, source.rig.cameras[0], pose, background, 2.2)
        .convertTo(image, CV_8UC3, 255.0);
    source.images.push_back({image});
    source.world_from_obj.push_back(pose);
  }
  Mesh larger = cube;
  larger.Scale(1.01f);
  source.models = {cube, MakeLetteredCube(0.096, 64), larger};
  return source;
}

SoakOptions FrequentFaults(int frames) {
  SoakOptions o;
  o.frames = frames;
  o.seed = 7;
  o.black_rate = 0.015;
  o.noise_rate = 0.015;
  o.missing_rate = 0.015;
  o.jump_rate = 0.02;
  o.min_jump_frames = 5;
  o.max_jump_frames = 20;
  o.model_swap_rate = 0.05;
  o.reinitialize_after_lost = 10;
  o.memory_sample_frames = 50;
  return o;
}

TEST(Soak, ShortRunHasNoNaNPoseAndNoException) {
  const SoakSource source = SmallSource(40);
  const SoakResult r = RunSoak(source, TrackerOptions(), FrequentFaults(300));
  SCOPED_TRACE(r.BriefReport());
  EXPECT_EQ(r.frames, 300);
  EXPECT_EQ(r.nan_poses, 0);
  EXPECT_EQ(r.exceptions, 0);
  // The faults happened and the tracker went through losses and recoveries.
  EXPECT_GT(r.black_frames + r.noise_frames + r.missing_frames, 10);
  EXPECT_GT(r.jumps, 0);
  EXPECT_GE(r.replays, 5);
  EXPECT_GT(r.model_swaps, 5);
  EXPECT_GT(r.lost_frames, r.black_frames + r.noise_frames + r.missing_frames - 10);
  EXPECT_GE(r.reacquisitions + r.reinitializations, 2);
  EXPECT_EQ(r.frames, r.tracking_frames + r.lost_frames);
  // Most frames of the sequence are tracked, and tracked right.
  EXPECT_GT(r.within_5cm_5deg, r.sequence_frames / 2);
  EXPECT_LE(r.tracking_far, r.sequence_frames / 20);
  EXPECT_LE(r.confident_far, r.sequence_frames / 50);
  // Memory sampled at 0, 50, ..., 300.
  ASSERT_EQ(r.memory.size(), 7u);
  EXPECT_EQ(r.memory.back().frame, 300);
  EXPECT_GT(r.StartResidentBytes(), 0);
  EXPECT_GE(r.MaxResidentBytes(), r.EndResidentBytes());
}

TEST(Soak, SameSeedSameRun) {
  const SoakSource source = SmallSource(12);
  SoakOptions o = FrequentFaults(40);
  o.black_rate = o.noise_rate = o.missing_rate = 0.05;
  const SoakResult a = RunSoak(source, TrackerOptions(), o);
  const SoakResult b = RunSoak(source, TrackerOptions(), o);
  EXPECT_EQ(a.lost_frames, b.lost_frames);
  EXPECT_EQ(a.black_frames, b.black_frames);
  EXPECT_EQ(a.noise_frames, b.noise_frames);
  EXPECT_EQ(a.missing_frames, b.missing_frames);
  EXPECT_EQ(a.jumps, b.jumps);
  EXPECT_EQ(a.model_swaps, b.model_swaps);
  EXPECT_EQ(a.within_5cm_5deg, b.within_5cm_5deg);
  o.seed = 8;
  const SoakResult c = RunSoak(source, TrackerOptions(), o);
  EXPECT_NE(std::tuple(a.black_frames, a.noise_frames, a.missing_frames, a.jumps),
            std::tuple(c.black_frames, c.noise_frames, c.missing_frames, c.jumps));
}

TEST(Soak, BadOptionsAndSourceThrow) {
  SoakOptions o;
  o.frames = 0;
  EXPECT_THROW(o.Check(), Error);
  o = SoakOptions();
  o.black_rate = o.noise_rate = o.missing_rate = 0.5;
  testing::ExpectError([&] { o.Check(); }, {"black_rate + noise_rate + missing_rate"});
  o = SoakOptions();
  o.min_jump_frames = 30;
  o.max_jump_frames = 10;
  testing::ExpectError([&] { o.Check(); }, {"min_jump_frames"});
  SoakSource source = SmallSource(2);
  source.world_from_obj.pop_back();
  testing::ExpectError([&] { RunSoak(source, TrackerOptions(), SoakOptions()); },
                       {"2 frames but 1 poses"});
  source = SmallSource(2);
  source.images[1].push_back(source.images[1][0]);
  testing::ExpectError([&] { source.Check(); }, {"frame 1 has 2 images"});
  source = SmallSource(2);
  source.models.clear();
  testing::ExpectError([&] { source.Check(); }, {"no model"});
}

}  // namespace
}  // namespace unseen
