// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/system/tracking_session.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "unseen/util/error.h"

namespace unseen {
namespace {

// The true pose of frame `i`: the object turns about z and moves along x.
Rigid3d TruePose(int i) {
  return Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * i, Eigen::Vector3d::UnitZ())),
                 Eigen::Vector3d(0.01 * i, 0.0, 0.5));
}

// `frames` frames of one camera (no pixels), ids from 100, with ground truth when asked.
class FakeSource : public FrameSource {
 public:
  FakeSource(int frames, bool truth) : frames_(frames), truth_(truth) {}
  const Rig& rig() const override { return rig_; }
  double fps() const override { return 25.0; }
  std::optional<Frame> Next() override {
    if (reads_ >= frames_) return std::nullopt;
    Frame frame;
    frame.frame_id = 100 + reads_;
    frame.time_s = reads_ / 25.0;
    frame.images = {cv::Mat()};
    ++reads_;
    return frame;
  }
  std::optional<Rigid3d> GroundTruth(int n) const override {
    if (!truth_ || n < 0 || n >= frames_) return std::nullopt;
    return TruePose(n);
  }
  std::string name() const override { return "fake"; }
  int reads() const { return reads_; }

 private:
  Rig rig_;
  int frames_;
  bool truth_;
  std::atomic<int> reads_{0};
};

TrackResult Result(const Rigid3d& world_from_obj, TrackStatus status) {
  TrackResult r;
  r.world_from_obj = world_from_obj;
  r.status = status;
  r.confidence = status == TrackStatus::kTracking ? 0.9 : 0.0;
  return r;
}

// Every test runs with the next frame read on another thread and without.
class TrackingSessionTest : public ::testing::TestWithParam<bool> {
 protected:
  SessionOptions Options() const {
    SessionOptions options;
    options.name = "test";
    options.read_ahead = GetParam();
    return options;
  }
};

TEST_P(TrackingSessionTest, CountsStatusesAndWritesOneRecordPerPose) {
  FakeSource source(6, false);
  SessionOptions options = Options();
  options.poses_file =
      (std::filesystem::temp_directory_path() /
       (std::string("tracking_session_test_") + (GetParam() ? "ahead" : "inline") + ".csv"))
          .string();
  int calls = 0;
  const SessionSummary summary = TrackingSession(source, options).Run([&](const Frame& frame) {
    const int i = calls++;
    if (i < 2) {  // no pose yet
      SessionStep step;
      step.status = "learning";
      return step;
    }
    const TrackStatus status = i == 4 ? TrackStatus::kLost : TrackStatus::kTracking;
    // The third frame's time is given (a search done before it).
    return SessionStep::FromTrack(Result(TruePose(i), status),
                                  i == 2 ? std::optional<double>(40.0) : std::nullopt);
  });
  EXPECT_EQ(calls, 6);
  EXPECT_EQ(summary.frames, 6);
  EXPECT_EQ(summary.count("learning"), 2);
  EXPECT_EQ(summary.count("tracking"), 3);
  EXPECT_EQ(summary.count("lost"), 1);
  EXPECT_EQ(summary.count("no object"), 0);
  EXPECT_EQ(summary.tracking, 3);
  EXPECT_EQ(summary.truth_frames, 0);
  EXPECT_EQ(summary.given.frames, 0);
  EXPECT_FALSE(summary.stopped);
  EXPECT_GE(summary.process_ms, 40.0);
  EXPECT_GT(summary.fps(), 0.0);

  ASSERT_EQ(summary.records.size(), 4u);
  const std::vector<PoseRecord> written = ReadPoseStream(options.poses_file);
  ASSERT_EQ(written.size(), 4u);
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(written[k].frame, 102 + k);
    EXPECT_NEAR(written[k].time_s, (2 + k) / 25.0, 1e-12);
    EXPECT_EQ(written[k].status, summary.records[k].status);
    EXPECT_LT(Difference(written[k].world_from_obj, TruePose(2 + k)).translation, 1e-12);
    ASSERT_TRUE(written[k].process_ms.has_value());
    EXPECT_EQ(*written[k].process_ms, *summary.records[k].process_ms);
  }
  EXPECT_EQ(written[2].status, TrackStatus::kLost);
  EXPECT_EQ(*written[0].process_ms, 40.0);
  std::filesystem::remove(options.poses_file);
}

TEST_P(TrackingSessionTest, ScoresAsGivenAndAfterAligningTheFirstTrackedPose) {
  // The step's object frame is the true one moved by a fixed offset (an unknown object's
  // frame chosen by the system): 3 cm and 10 degrees.
  const Rigid3d true_obj_from_obj(
      Eigen::Quaterniond(Eigen::AngleAxisd(10.0 * M_PI / 180.0, Eigen::Vector3d::UnitX())),
      Eigen::Vector3d(0.03, 0.0, 0.0));
  FakeSource source(8, true);
  int calls = 0;
  const SessionSummary summary = TrackingSession(source, Options()).Run([&](const Frame&) {
    const int i = calls++;
    if (i == 0) return SessionStep{};  // no pose: counted with the truth only
    Rigid3d estimate = TruePose(i) * true_obj_from_obj;
    // Frame 5 is off by 10 cm more (a bad frame after the alignment).
    if (i == 5)
      estimate =
          Rigid3d(estimate.rotation(), estimate.translation() + Eigen::Vector3d(0.1, 0.0, 0.0));
    // Frame 6 is lost: scored as given, not after aligning.
    return SessionStep::FromTrack(
        Result(estimate, i == 6 ? TrackStatus::kLost : TrackStatus::kTracking));
  });
  EXPECT_EQ(summary.frames, 8);
  EXPECT_EQ(summary.truth_frames, 8);
  // As given: every pose is 3 cm (or more) and 10 degrees off.
  EXPECT_EQ(summary.given.frames, 7);
  EXPECT_NEAR(summary.given.max_deg, 10.0, 1e-9);
  EXPECT_NEAR(summary.given.mean_deg(), 10.0, 1e-9);
  EXPECT_GE(summary.given.max_mm, 100.0);
  // After aligning the first tracked pose the offset is gone: only frame 5 is off.
  ASSERT_TRUE(summary.obj_from_true_obj.has_value());
  EXPECT_LT(Difference(*summary.obj_from_true_obj, true_obj_from_obj.Inverse()).translation, 1e-12);
  EXPECT_EQ(summary.aligned.frames, 6);
  EXPECT_NEAR(summary.aligned.max_deg, 0.0, 1e-6);
  EXPECT_NEAR(summary.aligned.max_mm, 100.0, 1e-6);
  EXPECT_NEAR(summary.aligned.mean_mm(), 100.0 / 6, 1e-6);
  EXPECT_EQ(summary.within, 5);
}

// A step that tracks each frame at its true pose, counting its calls.
TrackingSession::Step TrackedAtTruth(int* calls) {
  return [calls](const Frame&) {
    return SessionStep::FromTrack(Result(TruePose((*calls)++), TrackStatus::kTracking));
  };
}

// max_frames ends the session without reading further; so does a source that stops
// delivering before it.
TEST_P(TrackingSessionTest, MaxFramesOrTheSourcesEndEndsTheSession) {
  for (const auto& [available, max_frames, expected] : {std::tuple{10, 3, 3}, {2, 5, 2}}) {
    FakeSource source(available, true);
    SessionOptions options = Options();
    options.max_frames = max_frames;
    int calls = 0;
    const SessionSummary summary = TrackingSession(source, options).Run(TrackedAtTruth(&calls));
    EXPECT_EQ(calls, expected);
    EXPECT_EQ(summary.frames, expected);
    EXPECT_EQ(source.reads(), expected);
    EXPECT_EQ(summary.records.size(), static_cast<size_t>(expected));
    EXPECT_EQ(summary.truth_frames, expected);
    EXPECT_EQ(summary.within, expected);
    EXPECT_FALSE(summary.stopped);
  }
}

TEST_P(TrackingSessionTest, TheObserverOrAStopRequestEndsTheSession) {
  {
    FakeSource source(10, false);
    int observed = 0;
    const SessionSummary summary =
        TrackingSession(source, Options())
            .Run([](const Frame&) { return SessionStep{}; },
                 [&](const Frame& frame, const SessionStep&, const SessionFrame& seen) {
                   EXPECT_EQ(seen.index, observed);
                   EXPECT_EQ(frame.frame_id, 100 + observed);
                   return ++observed < 2;
                 });
    EXPECT_EQ(observed, 2);
    EXPECT_EQ(summary.frames, 2);
    EXPECT_TRUE(summary.stopped);
    EXPECT_LE(source.reads(), 3);  // at most the frame read ahead
  }
  {
    FakeSource source(10, false);
    TrackingSession session(source, Options());
    int calls = 0;
    const SessionSummary summary = session.Run([&](const Frame&) {
      if (++calls == 3) session.RequestStop();  // the frame in hand is finished
      return SessionStep::FromTrack(Result(Rigid3d(), TrackStatus::kTracking));
    });
    EXPECT_EQ(calls, 3);
    EXPECT_EQ(summary.frames, 3);
    EXPECT_EQ(summary.records.size(), 3u);
    EXPECT_TRUE(summary.stopped);
  }
}

TEST_P(TrackingSessionTest, WhatTheStepThrowsPassesThrough) {
  FakeSource source(5, false);
  TrackingSession session(source, Options());
  EXPECT_THROW(session.Run([](const Frame& frame) -> SessionStep {
    if (frame.frame_id == 101) throw std::runtime_error("step failed");
    return {};
  }),
               std::runtime_error);
}

INSTANTIATE_TEST_SUITE_P(ReadAhead, TrackingSessionTest, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? "ReadAhead" : "Inline";
                         });

TEST(SessionOptions, CheckRejectsNonsense) {
  SessionOptions options;
  EXPECT_NO_THROW(options.Check());
  options.max_frames = -1;
  EXPECT_THROW(options.Check(), Error);
  options = SessionOptions();
  options.within_deg = 0.0;
  EXPECT_THROW(options.Check(), Error);
  options = SessionOptions();
  options.name.clear();
  EXPECT_THROW(options.Check(), Error);
  FakeSource source(1, false);
  options = SessionOptions();
  options.within_m = -1.0;
  EXPECT_THROW(TrackingSession(source, options), Error);
}

// A sequence from frame 3 whose first frame was read already: that frame comes first, then
// the sequence's from index 4; the ground truth follows the sequence's indices.
TEST(SequenceFrameSource, ReturnsAFrameReadAlreadyAndTheSequencesTruth) {
  const std::string path =
      std::string(UNSEEN_SOURCE_DIR) + "/../shared/data/sequences/cube_clutter_sidelight";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not found";
  const Sequence sequence = Sequence::Open(path);
  Frame read = sequence.ReadFrame(3);
  read.time_s = -1.0;  // marks the frame given
  SequenceFrameSource source(&sequence, 3, read);
  EXPECT_EQ(source.sequence(), &sequence);
  SessionOptions options;
  options.max_frames = 2;
  std::vector<Frame> seen;
  const SessionSummary summary = TrackingSession(source, options).Run([&](const Frame& frame) {
    seen.push_back(frame);
    return SessionStep::FromTrack(
        Result(*sequence.GroundTruth(2 + static_cast<int>(seen.size())), TrackStatus::kTracking));
  });
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0].time_s, -1.0);
  EXPECT_EQ(seen[1].frame_id, sequence.frame_id(4));
  EXPECT_EQ(summary.truth_frames, 2);
  EXPECT_NEAR(summary.given.max_mm, 0.0, 1e-9);
  ASSERT_TRUE(source.GroundTruth(1).has_value());
  EXPECT_EQ(source.GroundTruth(1)->translation(), sequence.GroundTruth(4)->translation());
  EXPECT_FALSE(source.GroundTruth(sequence.num_frames()).has_value());
  EXPECT_THROW(SequenceFrameSource(&sequence, sequence.num_frames()), Error);
}

}  // namespace
}  // namespace unseen
