// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/system/tracking_session.h"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <future>
#include <memory>
#include <utility>

#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/timer.h"

namespace unseen {

void SessionOptions::Check() const {
  UNSEEN_CHECK(!name.empty(), "session: name is empty");
  UNSEEN_CHECK(max_frames >= 0, "{}: max_frames {} must be >= 0 (0: all)", name, max_frames);
  UNSEEN_CHECK(std::isfinite(within_m) && within_m > 0.0, "{}: within_m {} must be > 0", name,
               within_m);
  UNSEEN_CHECK(std::isfinite(within_deg) && within_deg > 0.0, "{}: within_deg {} must be > 0", name,
               within_deg);
}

SessionStep SessionStep::FromTrack(TrackResult result, std::optional<double> process_ms) {
  SessionStep step;
  step.status = ToString(result.status);
  step.tracking = result.status == TrackStatus::kTracking;
  step.track = std::move(result);
  step.process_ms = process_ms;
  return step;
}

void SessionErrors::Add(const PoseDifference& d) {
  const double mm = 1e3 * d.translation, deg = d.rotation_rad * 180.0 / M_PI;
  sum_mm += mm;
  sum_deg += deg;
  max_mm = std::max(max_mm, mm);
  max_deg = std::max(max_deg, deg);
  ++frames;
}

int SessionSummary::count(const std::string& status) const {
  const auto it = statuses.find(status);
  return it == statuses.end() ? 0 : it->second;
}

TrackingSession::TrackingSession(FrameSource& source, const SessionOptions& options)
    : source_(source), options_((options.Check(), options)) {}

SessionSummary TrackingSession::Run(const Step& step, const Observer& observe) {
  std::unique_ptr<PoseStreamWriter> writer;
  if (!options_.poses_file.empty()) {
    writer = std::make_unique<PoseStreamWriter>(options_.poses_file);
  }
  SessionSummary summary;
  auto more = [&](int processed) {
    return (options_.max_frames <= 0 || processed < options_.max_frames) && !stop_;
  };
  auto read = [this] { return std::async(std::launch::async, [this] { return source_.Next(); }); };
  std::future<std::optional<Frame>> next;
  if (options_.read_ahead && more(0)) next = read();
  std::clock_t cpu_ticks = 0;
  while (more(summary.frames)) {
    const std::optional<Frame> frame = options_.read_ahead ? next.get() : source_.Next();
    if (!frame) break;
    SessionFrame seen;
    seen.index = summary.frames;
    if (options_.read_ahead && more(seen.index + 1)) next = read();

    const std::clock_t cpu_start = std::clock();
    Timer timer;
    const SessionStep s = step(*frame);
    const double step_ms = timer.ElapsedMilliseconds();
    cpu_ticks += std::clock() - cpu_start;
    seen.process_ms = s.process_ms.value_or(step_ms);
    summary.process_ms += seen.process_ms;
    ++summary.frames;
    ++summary.statuses[s.status];
    summary.tracking += s.tracking;
    if (!s.note.empty()) {
      UNSEEN_LOG_INFO("{}: frame {}: {}: {}", options_.name, frame->frame_id, s.status, s.note);
    }

    seen.truth = source_.GroundTruth(seen.index);
    summary.truth_frames += seen.truth.has_value();
    if (s.track) {
      summary.stage_times += s.track->summary.times;
      const PoseRecord record =
          s.track->ToPoseRecord(frame->frame_id, frame->time_s, seen.process_ms);
      if (writer) writer->Write(record);
      summary.records.push_back(record);
    }
    if (s.track && seen.truth) {
      seen.error = Difference(s.track->world_from_obj, *seen.truth);
      summary.given.Add(*seen.error);
      if (s.tracking) {
        if (!summary.obj_from_true_obj) {
          summary.obj_from_true_obj = s.track->world_from_obj.Inverse() * *seen.truth;
        }
        const PoseDifference d =
            Difference(s.track->world_from_obj * *summary.obj_from_true_obj, *seen.truth);
        summary.aligned.Add(d);
        summary.within += d.translation < options_.within_m &&
                          d.rotation_rad * 180.0 / M_PI < options_.within_deg;
      }
    }
    if (observe && !observe(*frame, s, seen)) {
      summary.stopped = true;
      break;
    }
  }
  summary.stopped = summary.stopped || stop_;
  summary.cpu_ms = 1e3 * static_cast<double>(cpu_ticks) / CLOCKS_PER_SEC;
  return summary;
}

}  // namespace unseen
