// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// A soak run: the tracker over a long stream made by playing a short sequence with known
// poses again and again, with the faults of a real stream injected at random (seeded):
// black frames, frames of pure noise, frames with no image at all, jumps ahead in the
// sequence, the model replaced, and the jump back to the first frame at every replay.
// The tracker loses the object and finds it again many times; the run counts what
// happened (lost frames, re-acquisitions, NaN poses, exceptions, confident poses far from
// the truth) and samples the resident memory, which must stay flat.
#pragma once

#include <cstdint>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/mesh/mesh.h"
#include "unseen/track/tracker_options.h"

namespace unseen {

// The sequence a soak run plays: per frame one image per rig camera (CV_8UC3 or CV_32FC3,
// of the camera's size) and the true pose; the models the tracker is given in turn
// (models[0] first; each swap takes the next, cyclically).
struct SoakSource {
  Rig rig;
  std::vector<std::vector<cv::Mat>> images;  // [frame][camera]
  std::vector<Rigid3d> world_from_obj;       // [frame], metres
  std::vector<Mesh> models;                  // metres, object frame
  // Throws unseen::Error for an empty sequence, frames and poses that differ in number, a
  // frame without one image per camera, no model or an invalid pose.
  void Check() const;
};

struct SoakOptions {
  int frames = 10000;  // frames to track
  uint64_t seed = 1;   // of every random choice of the run
  // Per frame, the probability that a fault starts there; black, noise and missing-image
  // faults last 1 to max_burst_frames frames (uniform). The sequence plays on under them.
  double black_rate = 0.004;    // all-black images
  double noise_rate = 0.004;    // uniform noise in [0, 1] per pixel and channel
  double missing_rate = 0.004;  // no image from any camera (Tracker::SkipFrame)
  int max_burst_frames = 4;
  // A jump ahead by min_jump_frames to max_jump_frames frames of the sequence (uniform).
  double jump_rate = 0.003;
  int min_jump_frames = 10;
  int max_jump_frames = 60;
  double model_swap_rate = 0.01;  // Tracker::SetModel with the next model
  // After this many lost frames in a row the run re-initialises the tracker at the true
  // pose, as an application's object detector would; 0 = never.
  int reinitialize_after_lost = 30;
  // A frame of the sequence reported kTracking with a pose further than this from the
  // truth counts as `tracking_far`, and as `confident_far` (a confident wrong pose) when
  // its confidence is at least FailureOptions::lost_confidence; metres and radians.
  double far_translation_m = 0.05;
  double far_rotation_rad = 5.0 * 3.14159265358979323846 / 180.0;
  int memory_sample_frames = 100;  // resident memory sampled every this many frames
  void Check() const;
};

struct SoakResult {
  int frames = 0;             // frames tracked (Track or SkipFrame calls)
  int sequence_frames = 0;    // of them, frames of the sequence (no fault injected)
  int lost_frames = 0;        // reported kLost (injected faults included)
  int tracking_frames = 0;    // reported kTracking
  int reacquisitions = 0;     // the tracker went from lost to tracking by itself
  int reinitializations = 0;  // re-initialised by the run (SoakOptions::reinitialize_after_lost)
  int within_5cm_5deg = 0;    // sequence frames reported kTracking within 5 cm and 5 degrees
  int tracking_far = 0;       // sequence frames reported kTracking far from the truth
  // Of them, those not flagged by their confidence: the first bad frames of a loss are
  // still reported kTracking (FailureOptions::lost_after_frames) but below lost_confidence.
  int confident_far = 0;
  int nan_poses = 0;   // results with a non-finite pose or confidence (must be 0)
  int exceptions = 0;  // exceptions thrown by the tracker (must be 0)
  std::vector<std::string> exception_messages;  // the first few
  // What was injected.
  int black_frames = 0, noise_frames = 0, missing_frames = 0;
  int jumps = 0, replays = 0, model_swaps = 0;
  double track_seconds = 0.0;      // wall clock in Track/SkipFrame/SetModel
  double track_cpu_seconds = 0.0;  // process CPU time (all threads) in the same calls
  struct MemorySample {
    int frame = 0;
    int64_t resident_bytes = 0;
  };
  std::vector<MemorySample> memory;  // at frame 0, every memory_sample_frames, at the end

  double Fps() const { return track_seconds > 0.0 ? frames / track_seconds : 0.0; }
  double CpuMsPerFrame() const { return frames > 0 ? 1e3 * track_cpu_seconds / frames : 0.0; }
  int64_t StartResidentBytes() const;
  int64_t EndResidentBytes() const;
  int64_t MaxResidentBytes() const;
  // Mean resident memory of the last quarter of the samples minus that of the first
  // quarter, bytes: a leak of L bytes per frame shows as about 3/4 L frames.
  double ResidentGrowthBytes() const;
  // One line of counts.
  std::string BriefReport() const;
};

// Plays `source` for options.frames frames through a Tracker made with `tracker_options`,
// initialised at the first true pose. `progress` (may be empty) is called after every
// memory sample. Throws unseen::Error for invalid options or source; what the tracker
// throws is counted, not thrown (the run re-initialises it and goes on).
SoakResult RunSoak(const SoakSource& source, const TrackerOptions& tracker_options,
                   const SoakOptions& options,
                   const std::function<void(const SoakResult&)>& progress = {});

}  // namespace unseen
