// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// One tracking session: the frame loop that `unseen track`, `unseen run` and the tracker
// benchmark share. Frames come from a FrameSource (the next one optionally read on another
// thread while the current one is processed); a per-frame step (the tracker, the system)
// makes the frame's pose; the session times the step, writes the pose stream, counts the
// statuses and scores the poses against the source's ground truth when it has some.
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "unseen/geometry/rigid3.h"
#include "unseen/io/pose_stream.h"
#include "unseen/system/frame_source.h"
#include "unseen/track/tracker.h"

namespace unseen {

struct SessionOptions {
  std::string name = "session";  // names the session in log lines ("track", "run")
  int max_frames = 0;            // process at most this many frames; 0: all the source has
  // Read the next frame on another thread while the current one is processed (one read at
  // a time, in order). The step then shares the cores with the reading.
  bool read_ahead = true;
  std::string poses_file;  // pose stream to write (.csv or .jsonl); empty: none
  // "Within" after aligning the first tracked pose: both below these (the RBOT criterion).
  double within_m = 0.05;
  double within_deg = 5.0;
  void Check() const;
};

// What the step made of one frame.
struct SessionStep {
  std::optional<TrackResult> track;  // the frame's pose; std::nullopt: no pose, no record
  std::string status;                // counted in SessionSummary::statuses
  bool tracking = false;             // a tracked pose: scored after aligning the first one
  std::string note;                  // logged with the frame when not empty
  std::optional<double> process_ms;  // the frame's time when not the step's own (ms)

  // A tracker's result: its status, tracking when it is TrackStatus::kTracking.
  static SessionStep FromTrack(TrackResult result, std::optional<double> process_ms = std::nullopt);
};

// One processed frame as the session saw it (given to the observer).
struct SessionFrame {
  int index = 0;                        // among the frames processed, from 0
  double process_ms = 0.0;              // the step's wall time, or SessionStep::process_ms
  std::optional<Rigid3d> truth;         // true world_from_obj, when the source has it
  std::optional<PoseDifference> error;  // the pose against `truth` as given
};

// Errors against ground truth: translation in mm, rotation in degrees.
struct SessionErrors {
  int frames = 0;  // frames counted
  double sum_mm = 0.0, max_mm = 0.0, sum_deg = 0.0, max_deg = 0.0;
  double mean_mm() const { return frames > 0 ? sum_mm / frames : 0.0; }
  double mean_deg() const { return frames > 0 ? sum_deg / frames : 0.0; }
  void Add(const PoseDifference& d);
};

struct SessionSummary {
  int frames = 0;                       // frames processed
  double process_ms = 0.0;              // sum of the frames' times
  double cpu_ms = 0.0;                  // process CPU time in the steps (all threads)
  StageTimes stage_times;               // sum over the frames with a pose
  std::map<std::string, int> statuses;  // frames per SessionStep::status
  int tracking = 0;                     // frames whose step said tracking
  std::vector<PoseRecord> records;      // one per frame with a pose, as written
  int truth_frames = 0;                 // frames with ground truth
  // Every pose against the ground truth as given.
  SessionErrors given;
  // Tracked poses after aligning the first one to the truth (removes a fixed change of
  // object frame, as `eval --align-first` does), and how many of them are within
  // SessionOptions::within_m / within_deg.
  std::optional<Rigid3d> obj_from_true_obj;
  SessionErrors aligned;
  int within = 0;
  bool stopped = false;  // the observer or RequestStop ended the session early

  double fps() const { return process_ms > 0.0 ? 1e3 * frames / process_ms : 0.0; }
  double mean_ms() const { return frames > 0 ? process_ms / frames : 0.0; }
  int count(const std::string& status) const;
};

class TrackingSession {
 public:
  // Processes one frame. The frame's Frame::errors are the step's to report.
  using Step = std::function<SessionStep(const Frame&)>;
  // Sees each frame after its pose is written and scored; returns false to end the session.
  using Observer = std::function<bool(const Frame&, const SessionStep&, const SessionFrame&)>;

  // `source` must outlive the session. Throws unseen::Error for invalid options.
  explicit TrackingSession(FrameSource& source, const SessionOptions& options = {});

  // Runs `step` on each frame until the source ends, max_frames, the observer says stop or
  // RequestStop. Throws unseen::Error when the pose file cannot be written; what the
  // source and the step throw passes through.
  SessionSummary Run(const Step& step, const Observer& observe = nullptr);

  // From any thread: the session ends after the frame in hand.
  void RequestStop() { stop_ = true; }

 private:
  FrameSource& source_;
  SessionOptions options_;
  std::atomic<bool> stop_{false};
};

}  // namespace unseen
