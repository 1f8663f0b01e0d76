// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/select/known_model_pose.h"

#include <sys/resource.h>

#include <atomic>
#include <chrono>
#include <exception>
#include <future>
#include <memory>
#include <system_error>
#include <utility>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/timer.h"

namespace unseen {
namespace {

double BoxIou(const PixelRect& a, const PixelRect& b) {
  const long both = a.Intersect(b).area();
  const long either = a.area() + b.area() - both;
  return either > 0 ? static_cast<double>(both) / either : 0.0;
}

}  // namespace

void KnownModelPoseOptions::Check() const {
  views.Check();
  UNSEEN_CHECK(max_candidates >= 1 && max_candidates <= 1000,
               "known-model pose: max_candidates {} not in [1, 1000]", max_candidates);
  UNSEEN_CHECK(min_separation_deg >= 0.0 && min_separation_deg < 180.0,
               "known-model pose: min_separation_deg {} not in [0, 180)", min_separation_deg);
  UNSEEN_CHECK(min_confidence >= 0.0 && min_confidence <= 1.0,
               "known-model pose: min_confidence {} not in [0, 1]", min_confidence);
  UNSEEN_CHECK(min_appearance_fit >= 0.0 && min_appearance_fit <= 1.0,
               "known-model pose: min_appearance_fit {} not in [0, 1]", min_appearance_fit);
  UNSEEN_CHECK(min_silhouette_fit >= 0.0 && min_silhouette_fit <= 1.0,
               "known-model pose: min_silhouette_fit {} not in [0, 1]", min_silhouette_fit);
  UNSEEN_CHECK(min_box_iou >= 0.0 && min_box_iou <= 1.0,
               "known-model pose: min_box_iou {} not in [0, 1]", min_box_iou);
}

std::string KnownModelPoseResult::BriefReport() const {
  return fmt::format(
      "{} (confidence {:.2f}, fit {:.2f}, box IoU {:.2f}, candidate {} of {}; "
      "views {:.1f} ms, alignments {:.1f} ms)",
      found ? "found" : "no pose", confidence, fit, box_iou, candidate, candidates_aligned,
      match_ms, align_ms);
}

KnownModelPoser::KnownModelPoser(Tracker* tracker, const KnownModelPoseOptions& options)
    : tracker_(*tracker),
      options_((options.Check(), options)),
      views_(tracker->given_model(), options.views) {}

KnownModelPoser::KnownModelPoser(Tracker* tracker, ViewBank views,
                                 const KnownModelPoseOptions& options)
    : tracker_(*tracker), options_((options.Check(), options)), views_(std::move(views)) {
  options_.views = views_.options();  // as they were rendered
}

std::vector<Rigid3d> KnownModelPoser::Candidates(const Frame& frame, int camera,
                                                 const PixelRect& box) const {
  const Rig& rig = tracker_.rig();
  UNSEEN_CHECK(camera >= 0 && camera < rig.size(), "known-model pose: camera {} not in [0, {})",
               camera, rig.size());
  UNSEEN_CHECK(camera < static_cast<int>(frame.images.size()) && !frame.images[camera].empty(),
               "known-model pose: the frame has no image from camera {}", camera);
  const RigCamera& rig_camera = rig.cameras[camera];
  std::vector<Rigid3d> starts;
  for (const ViewMatch& match : views_.Match(frame.images[camera], box, options_.max_candidates,
                                             options_.min_separation_deg)) {
    starts.push_back(rig_camera.world_from_cam *
                     views_.CamFromObj(match, rig_camera.intrinsics, box));
  }
  return starts;
}

KnownModelPoseResult KnownModelPoser::Find(const Frame& frame, int camera, const PixelRect& box) {
  KnownModelPoseResult result;
  Timer timer;
  const std::vector<Rigid3d> starts = Candidates(frame, camera, box);
  result.match_ms = timer.ElapsedMilliseconds();
  timer.Restart();
  // Each candidate is judged as the tracker judges a first frame: Initialize (which forgets
  // everything learnt) and Track, so the colour statistics of the silhouette and the
  // choice between appearance and silhouette are made afresh at each start. The tracker's
  // confidence says whether the object is there; which orientation it has, it rarely
  // says (a cube turned by 90° fits its silhouette as well), so the candidates it accepts
  // are ranked by their fit: the share of the model's textured pixels that agree with the
  // image, or for a model without appearance the silhouette's agreement.
  const bool by_appearance =
      tracker_.given_model().HasAppearance() && tracker_.options().photometric.enabled;
  const RigCamera& rig_camera = tracker_.rig().cameras[camera];
  double best_fit = -1.0;
  for (int i = 0; i < static_cast<int>(starts.size()); ++i) {
    tracker_.Initialize(starts[i]);
    const TrackResult tracked = tracker_.Track(frame);
    ++result.candidates_aligned;
    const double fit = by_appearance ? tracked.summary.share
                                     : std::max(0.0, tracked.summary.region_counts.Agreement());
    const double box_iou =
        BoxIou(box, SilhouetteBox(tracker_.given_model(), rig_camera.intrinsics,
                                  rig_camera.cam_from_world() * tracked.world_from_obj));
    const bool accepted =
        tracked.status == TrackStatus::kTracking && tracked.confidence >= options_.min_confidence &&
        box_iou >= options_.min_box_iou &&
        fit >= (by_appearance ? options_.min_appearance_fit : options_.min_silhouette_fit);
    // Accepted candidates first, then by fit; unaccepted ones by confidence.
    const double rank = accepted ? 2.0 + fit : tracked.confidence;
    if (rank > best_fit) {
      best_fit = rank;
      result.candidate = i;
      result.confidence = tracked.confidence;
      result.fit = fit;
      result.box_iou = box_iou;
      result.world_from_obj = tracked.world_from_obj;
      result.found = accepted;
      result.tracked = tracked;
    }
  }
  // The tracker starts afresh at the refined pose: had it gone on from the candidate's
  // frame, its motion model would take the refinement for the object's velocity.
  if (result.found) tracker_.Initialize(result.world_from_obj);
  result.align_ms = timer.ElapsedMilliseconds();
  return result;
}

PixelRect SilhouetteBox(const Mesh& model, const PinholeCamera& camera,
                        const Rigid3d& cam_from_obj) {
  RenderOptions options;
  options.write_color = false;
  RenderBuffers buffers;
  Render(model, camera, cam_from_obj, camera.ImageRect(), options, &buffers);
  if (buffers.mask.empty()) return {};
  const cv::Rect bounds = cv::boundingRect(buffers.mask);
  if (bounds.empty()) return {};
  return {buffers.roi.x0 + bounds.x, buffers.roi.y0 + bounds.y,
          buffers.roi.x0 + bounds.x + bounds.width, buffers.roi.y0 + bounds.y + bounds.height};
}

BackgroundViewBank::BackgroundViewBank(std::shared_ptr<const Mesh> model,
                                       const ViewBankOptions& options) {
  UNSEEN_CHECK(model != nullptr, "BackgroundViewBank: no model");
  options.Check();
  try {
    done_ = std::async(std::launch::async, [this, model = std::move(model), options] {
      // Beside tracking, not in its way: the lowest priority for this thread and the ones
      // it starts (Linux's nice value is theirs, not the process's).
      setpriority(PRIO_PROCESS, 0, 19);
      Timer timer;
      auto bank = std::make_shared<ViewBank>(*model, options, &cancel_);
      UNSEEN_LOG_INFO("view-bank proposals: {} views rendered in {:.0f} ms beside tracking",
                      bank->size(), timer.ElapsedMilliseconds());
      return bank;
    });
  } catch (const std::system_error& e) {  // no thread to be had: TakeIfDone gives nothing
    UNSEEN_LOG_INFO("view-bank proposals: no thread to render them beside tracking ({})", e.what());
  }
}

BackgroundViewBank::~BackgroundViewBank() {
  cancel_ = true;
  if (done_.valid()) done_.wait();
}

void BackgroundViewBank::Wait() const {
  if (done_.valid()) done_.wait();
}

std::shared_ptr<ViewBank> BackgroundViewBank::TakeIfDone() {
  if (!done_.valid()) return nullptr;
  if (done_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
    cancel_ = true;
    done_.wait();
  }
  try {
    return done_.get();
  } catch (const std::exception& e) {  // cancelled, or the views could not be made
    UNSEEN_LOG_DEBUG("view-bank proposals: the render beside tracking gave none: {}", e.what());
    return nullptr;
  }
}

PoseProposer ViewBankProposer(Tracker* tracker, const KnownModelPoseOptions& options,
                              ViewBankBuild build) {
  UNSEEN_CHECK(tracker != nullptr, "ViewBankProposer: no tracker");
  std::shared_ptr<BackgroundViewBank> background;
  if (build == ViewBankBuild::kInBackground) {
    background = std::make_shared<BackgroundViewBank>(tracker->shared_given_model(), options.views);
  }
  return ViewBankProposer(tracker, options, std::move(background));
}

PoseProposer ViewBankProposer(Tracker* tracker, const KnownModelPoseOptions& options,
                              std::shared_ptr<BackgroundViewBank> background) {
  options.Check();
  UNSEEN_CHECK(tracker != nullptr, "ViewBankProposer: no tracker");
  // All copies of the proposer share `poser`: the first call makes it, the others use it.
  // Not for concurrent calls.
  auto poser = std::make_shared<std::shared_ptr<const KnownModelPoser>>();
  auto failed = std::make_shared<bool>(false);
  return [tracker, options, poser, failed, background](const Frame& frame, int camera,
                                                       const PixelRect& box) {
    if (*failed) return std::vector<Rigid3d>();
    try {
      if (!*poser) {
        const std::shared_ptr<ViewBank> done = background ? background->TakeIfDone() : nullptr;
        if (done) {
          *poser = std::make_shared<const KnownModelPoser>(tracker, std::move(*done), options);
        } else {
          Timer timer;
          *poser = std::make_shared<const KnownModelPoser>(tracker, options);
          UNSEEN_LOG_INFO("view-bank proposals: {} views rendered in {:.0f} ms",
                          options.views.num_directions * options.views.num_rolls,
                          timer.ElapsedMilliseconds());
        }
      }
      return (*poser)->Candidates(frame, camera, box);
    } catch (const std::exception& e) {
      *failed = !*poser;  // the views could not be made: no proposals from now on
      UNSEEN_LOG_INFO("view-bank proposals: none: {}", e.what());
      return std::vector<Rigid3d>();
    }
  };
}

}  // namespace unseen
