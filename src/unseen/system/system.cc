// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/system/system.h"

#include <fmt/format.h>

#include <opencv2/imgproc.hpp>

#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"

namespace unseen {

const char* ToString(SystemStatus status) {
  switch (status) {
    case SystemStatus::kLearning:
      return "learning";
    case SystemStatus::kNoObject:
      return "no object";
    case SystemStatus::kTracking:
      return "tracking";
    case SystemStatus::kLost:
      return "lost";
  }
  return "?";
}

SystemOptions::SystemOptions() {
  selection.rank_by_total_interest = true;
  selection.min_interest_share = 0.05;
  selection.min_mean_interest = 0.05;
}

void SystemOptions::Check() const {
  segmentation.Check();
  selection.Check();
  known_pose.Check();
  update.Check();
  tracked_motion.Check();
  UNSEEN_CHECK(rebuild_min_interest >= 0.0 && rebuild_min_interest < 1.0,
               "system: rebuild_min_interest {} not in [0, 1)", rebuild_min_interest);
  UNSEEN_CHECK(reselect_after_lost_frames >= 1,
               "system: reselect_after_lost_frames {} must be >= 1", reselect_after_lost_frames);
}

System::System(const Rig& rig, int reference, std::optional<Mesh> model, InterestFilterBank bank,
               const SystemOptions& options, const TrackerOptions& tracker_options,
               const ModellerOptions& modeller_options)
    : rig_(rig),
      reference_(reference),
      known_model_(model.has_value()),
      bank_(std::move(bank)),
      options_((options.Check(), options)),
      tracker_options_(tracker_options),
      segmenter_(options.segmentation),
      tracked_motion_(options.tracked_motion) {
  rig_.Check();
  UNSEEN_CHECK(reference >= 0 && reference < rig_.size(),
               "system: reference camera {} not in [0, {})", reference, rig_.size());
  UNSEEN_CHECK(bank_.size() > 0, "system: the interest filter bank is empty");
  if (known_model_) {
    tracker_ = std::make_unique<Tracker>(rig_, std::move(*model), tracker_options_);
    poser_ = std::make_unique<KnownModelPoser>(tracker_.get(), options_.known_pose);
    // A lost object found again by the re-acquisition's correlation is tried in the
    // orientations of the views that match it there (Tracker::SetPoseProposer).
    tracker_->SetPoseProposer(
        [poser = poser_.get()](const Frame& frame, int camera, const PixelRect& box) {
          return poser->Candidates(frame, camera, box);
        });
  } else {
    modeller_ = std::make_unique<Modeller>(rig_, reference_, modeller_options);
  }
}

System::~System() {
  updater_.reset();  // its builds refer to the tracker
}

bool System::Start(const Frame& frame, const RegionCandidate& region, const cv::Mat& labels,
                   SystemStep* step) {
  if (known_model_) {
    const PixelRect box =
        options_.regions == RegionSource::kMotion ? segmenter_.ObjectBox(region.box) : region.box;
    const KnownModelPoseResult found = poser_->Find(frame, reference_, box);
    step->note = fmt::format("known model in {}x{} at ({}, {}): {}", box.width(), box.height(),
                             box.x0, box.y0, found.BriefReport());
    if (!found.found) return false;
    step->track = found.tracked;
    return true;
  }
  // An unknown object: its frame at the region (SPEC 4.4) and a first model there.
  const bool image_depth = modeller_->options().depth.source != DepthSourceKind::kSensor;
  const cv::Mat mask =
      labels.empty() || (image_depth && !options_.first_model_from_motion_with_image_depth)
          ? cv::Mat()
          : cv::Mat(labels == region.label);
  // Measured depth and moving pixels: those pick the object's surface, which reaches as far
  // as it is connected in depth within the object's sphere (an untextured object moves
  // only in the blocks along its outline, and those hold the background's side too).
  const bool moved = !image_depth && !mask.empty() && options_.regions == RegionSource::kMotion;
  const MaskRole role = moved ? MaskRole::kSelects : MaskRole::kBounds;
  const std::optional<Rigid3d> start = modeller_->InitialPose(frame, region.box, mask, role);
  if (!start) {
    step->note = "no depth measured in the region: cannot place the object";
    return false;
  }
  const ModelBuild build =
      modeller_->Build(frame, *start, moved ? PixelRect() : region.box, mask, nullptr, role);
  if (!build.ok()) {
    step->note = "cannot model the object: " + build.why;
    return false;
  }
  updater_.reset();
  updater_ = std::make_unique<ModelUpdater>(modeller_.get(), options_.update);
  Mesh first = updater_->Start(build);
  const int triangles = first.num_triangles();
  tracker_ = std::make_unique<Tracker>(rig_, std::move(first), tracker_options_);
  tracker_->Initialize(build.world_from_obj);
  step->track = tracker_->Track(frame);
  step->note = fmt::format("modelled: {} triangles", triangles);
  return true;
}

cv::Mat System::MovingWithObject(const Frame& frame, const TrackResult& track, bool judge) {
  const std::optional<Rigid3d> previous = previous_tracked_;
  const bool tracked = track.status == TrackStatus::kTracking;
  previous_tracked_ = tracked ? std::optional<Rigid3d>(track.world_from_obj) : std::nullopt;
  const cv::Mat& image = frame.images[reference_];
  if (image.empty()) return cv::Mat();
  const RigCamera& camera = rig_.cameras[reference_];
  FilterFrame in;
  in.image = image;
  in.camera = camera.intrinsics;
  in.world_from_cam = camera.world_from_cam;
  in.time_s = frame.time_s;
  if (judge && tracked && previous) {
    in.world_from_obj = track.world_from_obj;
    in.previous_world_from_obj = *previous;
    if (!frame.depths.empty() && !frame.depths[reference_].empty()) {
      in.depth = frame.depths[reference_];
    } else {
      // No measured depth: the model's, rendered at the tracked pose (the filter takes the
      // origin's depth elsewhere).
      RenderBuffers render;
      Render(tracker_->model(), camera.intrinsics, camera.cam_from_world() * track.world_from_obj,
             camera.intrinsics.ImageRect(), RenderOptions{}, &render);
      in.depth = cv::Mat::zeros(image.size(), CV_32FC1);
      if (!render.roi.empty()) {
        render.depth.copyTo(in.depth(ToCvRect(render.roi)));
      }
    }
  }
  // Judged only around the object: its bounding sphere's square, half as large again.
  cv::Mat interest(image.size(), CV_32FC1, cv::Scalar(0.0f));
  if (in.world_from_obj) {
    Eigen::Vector3f centre;
    float radius = 0.0f;
    tracker_->model().BoundingSphere(&centre, &radius);
    const Eigen::Vector3d c =
        camera.cam_from_world() * (track.world_from_obj * centre.cast<double>());
    if (c.z() > 1e-3) {
      const Eigen::Vector2d px = camera.intrinsics.Project(c);
      const double r = 1.5 * camera.intrinsics.fx * radius / c.z();
      const cv::Rect around(cvFloor(px.x() - r), cvFloor(px.y() - r), cvCeil(2 * r), cvCeil(2 * r));
      interest(around & cv::Rect({}, image.size())).setTo(1.0f);
    }
  }
  tracked_motion_.Apply(in, &interest);  // keeps this image for the next frame
  if (!in.world_from_obj) return cv::Mat();
  // (A region left at 1 everywhere: the object hardly moved, nothing told.)
  cv::Mat moving = interest > options_.rebuild_min_interest;
  if (cv::countNonZero(interest == 1.0f) == cv::countNonZero(interest > 0.0f)) return cv::Mat();
  // Texture-less patches inside the object flow with their surroundings only roughly:
  // close small gaps.
  cv::morphologyEx(moving, moving, cv::MORPH_CLOSE,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(9, 9)));
  return moving;
}

SystemStep System::Step(const Frame& frame) {
  UNSEEN_CHECK(static_cast<int>(frame.images.size()) == rig_.size(),
               "system: frame {} has {} images for {} cameras", frame.frame_id, frame.images.size(),
               rig_.size());
  SystemStep step;
  step.frame_id = frame.frame_id;
  const cv::Mat& image = frame.images[reference_];
  cv::Mat labels;
  if (!image.empty()) {
    const RigCamera& camera = rig_.cameras[reference_];
    FilterFrame in;
    in.image = image;
    if (!frame.depths.empty()) in.depth = frame.depths[reference_];
    in.camera = camera.intrinsics;
    in.world_from_cam = camera.world_from_cam;
    in.time_s = frame.time_s;
    // Every frame teaches the background model and the motion segmentation, also while
    // tracking (SPEC 6).
    step.interest = bank_.Apply(in);
    const cv::Mat segments = segmenter_.Segment(image, step.interest);
    labels = options_.regions == RegionSource::kMotion
                 ? segments
                 : InterestRegions(step.interest, options_.selection.min_interest);
  }

  if (active_) {
    step.track = tracker_->Track(frame);
    if (updater_) {
      const cv::Mat moving =
          options_.rebuild_from_tracked_motion
              ? MovingWithObject(frame, *step.track, updater_->BuildsNext(step.track->confidence))
              : cv::Mat();
      updater_->AfterTracked(frame, *step.track, tracker_.get(), moving);
    }
    if (step.track->status == TrackStatus::kTracking) {
      lost_frames_ = 0;
      step.status = SystemStatus::kTracking;
      return step;
    }
    step.status = SystemStatus::kLost;
    if (++lost_frames_ < options_.reselect_after_lost_frames) return step;
    step.note = fmt::format("lost for {} frames: searching for the object again", lost_frames_);
    active_ = false;
    previous_tracked_.reset();
    lost_frames_ = 0;
    return step;
  }

  if (image.empty()) {
    step.status = SystemStatus::kNoObject;
    step.note = "no image from the reference camera";
    return step;
  }
  if (!bank_.ready()) {
    step.status = SystemStatus::kLearning;
    return step;
  }
  const cv::Mat depth = frame.depths.empty() ? cv::Mat() : frame.depths[reference_];
  const RegionSelection selection =
      SelectRegion(labels, step.interest, cv::Mat(), depth, rig_.cameras[reference_].intrinsics,
                   options_.selection);
  step.status = SystemStatus::kNoObject;
  for (const RegionCandidate& r : selection.regions) {
    if (r.candidate) step.candidates.push_back(r.box);
  }
  if (!selection.found()) return step;
  const RegionCandidate& region = selection.object();
  step.region = region.box;
  if (!Start(frame, region, labels, &step)) return step;
  active_ = true;
  lost_frames_ = 0;
  step.status = SystemStatus::kTracking;
  return step;
}

}  // namespace unseen
