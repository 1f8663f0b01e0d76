// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/soak.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <exception>
#include <random>

#include "unseen/track/tracker.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/memory.h"
#include "unseen/util/timer.h"

namespace unseen {
namespace {

constexpr int kMaxExceptionMessages = 10;

// Mean resident bytes of samples [begin, end).
double MeanResident(const std::vector<SoakResult::MemorySample>& samples, size_t begin,
                    size_t end) {
  double sum = 0.0;
  for (size_t i = begin; i < end; ++i) sum += double(samples[i].resident_bytes);
  return end > begin ? sum / double(end - begin) : 0.0;
}

enum class Fault { kNone, kBlack, kNoise, kMissing };

}  // namespace

void SoakSource::Check() const {
  rig.Check();
  UNSEEN_CHECK(!images.empty(), "soak source: no frames");
  UNSEEN_CHECK(images.size() == world_from_obj.size(), "soak source: {} frames but {} poses",
               images.size(), world_from_obj.size());
  UNSEEN_CHECK(!models.empty(), "soak source: no model");
  for (size_t f = 0; f < images.size(); ++f) {
    UNSEEN_CHECK(static_cast<int>(images[f].size()) == rig.size(),
                 "soak source: frame {} has {} images for a rig of {} cameras", f, images[f].size(),
                 rig.size());
    UNSEEN_CHECK(world_from_obj[f].IsValid(), "soak source: pose of frame {} ({}) is not valid", f,
                 world_from_obj[f].ToString());
  }
}

void SoakOptions::Check() const {
  UNSEEN_CHECK(frames > 0, "soak: frames {} must be > 0", frames);
  for (auto [name, rate] :
       {std::pair{"black_rate", black_rate}, std::pair{"noise_rate", noise_rate},
        std::pair{"missing_rate", missing_rate}, std::pair{"jump_rate", jump_rate},
        std::pair{"model_swap_rate", model_swap_rate}}) {
    UNSEEN_CHECK(rate >= 0.0 && rate <= 1.0, "soak: {} {} must be in [0, 1]", name, rate);
  }
  UNSEEN_CHECK(black_rate + noise_rate + missing_rate <= 1.0,
               "soak: black_rate + noise_rate + missing_rate = {} must be at most 1",
               black_rate + noise_rate + missing_rate);
  UNSEEN_CHECK(max_burst_frames >= 1, "soak: max_burst_frames {} must be >= 1", max_burst_frames);
  UNSEEN_CHECK(min_jump_frames >= 1 && min_jump_frames <= max_jump_frames,
               "soak: jumps of [{}, {}] frames: need 1 <= min_jump_frames <= max_jump_frames",
               min_jump_frames, max_jump_frames);
  UNSEEN_CHECK(reinitialize_after_lost >= 0, "soak: reinitialize_after_lost {} must be >= 0",
               reinitialize_after_lost);
  UNSEEN_CHECK(far_translation_m > 0.0 && far_rotation_rad > 0.0,
               "soak: far_translation_m {} and far_rotation_rad {} must be > 0", far_translation_m,
               far_rotation_rad);
  UNSEEN_CHECK(memory_sample_frames >= 1, "soak: memory_sample_frames {} must be >= 1",
               memory_sample_frames);
}

int64_t SoakResult::StartResidentBytes() const {
  return memory.empty() ? 0 : memory.front().resident_bytes;
}

int64_t SoakResult::EndResidentBytes() const {
  return memory.empty() ? 0 : memory.back().resident_bytes;
}

int64_t SoakResult::MaxResidentBytes() const {
  int64_t most = 0;
  for (const MemorySample& s : memory) most = std::max(most, s.resident_bytes);
  return most;
}

double SoakResult::ResidentGrowthBytes() const {
  const size_t n = memory.size();
  if (n < 2) return 0.0;
  const size_t quarter = std::max<size_t>(1, n / 4);
  return MeanResident(memory, n - quarter, n) - MeanResident(memory, 0, quarter);
}

std::string SoakResult::BriefReport() const {
  return fmt::format(
      "{} frames ({} of the sequence): {} tracking, {} lost, {} re-acquisitions, {} "
      "re-initialisations, {} within 5 cm/5 deg, {} tracking far ({} confident) | injected "
      "{} black, {} noise, {} missing, {} jumps, {} replays, {} model swaps | {} NaN poses, "
      "{} exceptions | {:.1f} fps, {:.2f} ms CPU a frame | RSS {:.1f} -> {:.1f} MB (max "
      "{:.1f}, growth {:+.1f})",
      frames, sequence_frames, tracking_frames, lost_frames, reacquisitions, reinitializations,
      within_5cm_5deg, tracking_far, confident_far, black_frames, noise_frames, missing_frames,
      jumps, replays, model_swaps, nan_poses, exceptions, Fps(), CpuMsPerFrame(),
      StartResidentBytes() / 1e6, EndResidentBytes() / 1e6, MaxResidentBytes() / 1e6,
      ResidentGrowthBytes() / 1e6);
}

SoakResult RunSoak(const SoakSource& source, const TrackerOptions& tracker_options,
                   const SoakOptions& options,
                   const std::function<void(const SoakResult&)>& progress) {
  source.Check();
  options.Check();
  const int num_frames = static_cast<int>(source.images.size());
  const int ncam = source.rig.size();
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  auto draw = [&rng](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };

  // The injected images, allocated once.
  std::vector<cv::Mat> black(ncam), noise(ncam), none(ncam);
  for (int c = 0; c < ncam; ++c) {
    const PinholeCamera& cam = source.rig.cameras[c].intrinsics;
    black[c] = cv::Mat(cam.height, cam.width, CV_32FC3, cv::Scalar::all(0.0));
    noise[c] = cv::Mat(cam.height, cam.width, CV_32FC3);
  }

  SoakResult result;
  auto sample_memory = [&](int frame) {
    result.memory.push_back({frame, ResidentMemoryBytes()});
    if (progress) progress(result);
  };
  Tracker tracker(source.rig, source.models[0], tracker_options);
  int model_index = 0;
  tracker.Initialize(source.world_from_obj[0]);
  sample_memory(0);

  int frame = 0;  // of the sequence
  Fault burst = Fault::kNone;
  int burst_left = 0;
  bool was_lost = false;
  int lost_run = 0;
  for (int i = 0; i < options.frames; ++i) {
    // Time passes: the next frame of the sequence, or one further on; after the last, the
    // first again.
    if (i > 0) {
      ++frame;
      if (uniform(rng) < options.jump_rate) {
        frame += draw(options.min_jump_frames, options.max_jump_frames);
        ++result.jumps;
      }
      if (frame >= num_frames) {
        frame = 0;
        ++result.replays;
      }
    }
    if (burst_left == 0) {
      const double u = uniform(rng);
      burst = u < options.black_rate                                               ? Fault::kBlack
              : u < options.black_rate + options.noise_rate                        ? Fault::kNoise
              : u < options.black_rate + options.noise_rate + options.missing_rate ? Fault::kMissing
                                                                                   : Fault::kNone;
      if (burst != Fault::kNone) burst_left = draw(1, options.max_burst_frames);
    }
    const Fault fault = burst_left > 0 ? burst : Fault::kNone;
    if (burst_left > 0) --burst_left;
    const bool swap = uniform(rng) < options.model_swap_rate;

    const std::vector<cv::Mat>* images = &source.images[frame];
    switch (fault) {
      case Fault::kNone:
        break;
      case Fault::kBlack:
        images = &black;
        ++result.black_frames;
        break;
      case Fault::kNoise: {
        cv::RNG noise_rng(rng());
        for (cv::Mat& n : noise) noise_rng.fill(n, cv::RNG::UNIFORM, 0.0, 1.0);
        images = &noise;
        ++result.noise_frames;
        break;
      }
      case Fault::kMissing:
        images = &none;
        ++result.missing_frames;
        break;
    }

    TrackResult r;
    bool thrown = false;
    Timer timer;
    const std::clock_t cpu_start = std::clock();
    try {
      if (swap) {
        model_index = (model_index + 1) % static_cast<int>(source.models.size());
        tracker.SetModel(source.models[model_index]);
        ++result.model_swaps;
      }
      r = tracker.Track(*images);
    } catch (const std::exception& e) {
      thrown = true;
      ++result.exceptions;
      if (static_cast<int>(result.exception_messages.size()) < kMaxExceptionMessages) {
        result.exception_messages.push_back(fmt::format("frame {}: {}", i, e.what()));
      }
      UNSEEN_LOG_WARN("soak frame {}: the tracker threw: {}", i, e.what());
    }
    result.track_seconds += timer.ElapsedSeconds();
    result.track_cpu_seconds += double(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    ++result.frames;
    if (thrown) {  // start again where the object is
      tracker.Initialize(source.world_from_obj[frame]);
      was_lost = false;
      lost_run = 0;
    } else {
      if (!r.world_from_obj.IsValid() || !std::isfinite(r.confidence)) ++result.nan_poses;
      if (r.status == TrackStatus::kLost) ++result.lost_frames;
      if (r.status == TrackStatus::kTracking) ++result.tracking_frames;
      if (fault == Fault::kNone) {
        ++result.sequence_frames;
        if (r.status == TrackStatus::kTracking && r.world_from_obj.IsValid()) {
          const PoseDifference d = Difference(r.world_from_obj, source.world_from_obj[frame]);
          if (d.translation <= 0.05 && d.rotation_rad <= 5.0 * M_PI / 180.0) {
            ++result.within_5cm_5deg;
          }
          if (d.translation > options.far_translation_m ||
              d.rotation_rad > options.far_rotation_rad) {
            ++result.tracking_far;
            if (r.confidence >= tracker_options.failure.lost_confidence) ++result.confident_far;
            UNSEEN_LOG_DEBUG(
                "soak frame {} (sequence frame {}): tracking {:.1f} mm {:.2f} deg "
                "from the truth, confidence {:.2f}",
                i, frame, 1e3 * d.translation, d.rotation_rad * 180.0 / M_PI, r.confidence);
          }
        }
      }
      // Transitions of the tracker's own state (a skipped frame reports kLost while the
      // tracker may still be tracking).
      const bool lost = tracker.status() == TrackStatus::kLost;
      if (was_lost && !lost) ++result.reacquisitions;
      lost_run = lost ? lost_run + 1 : 0;
      was_lost = lost;
      if (options.reinitialize_after_lost > 0 && lost_run >= options.reinitialize_after_lost) {
        tracker.Initialize(source.world_from_obj[frame]);
        ++result.reinitializations;
        was_lost = false;
        lost_run = 0;
      }
    }
    if ((i + 1) % options.memory_sample_frames == 0 || i + 1 == options.frames) {
      sample_memory(i + 1);
    }
  }
  return result;
}

}  // namespace unseen
