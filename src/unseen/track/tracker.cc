// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The tracker's model and the alignment of one frame: the multi-scale render-solve loop
// over every modality and camera (SPEC 3.1-3.8), on the whole pyramid or on a span of
// coarse levels. The state over frames is tracker_state.cc's, the judgement of an alignment
// tracker_judgement.cc's, the appearance tracker_appearance.cc's.
#include "unseen/track/tracker.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "unseen/image/filters.h"
#include "unseen/image/image_io.h"
#include "unseen/render/silhouette_share.h"
#include "unseen/track/flow_jacobian.h"
#include "unseen/track/reacquisition.h"
#include "unseen/track/virtual_image.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/timer.h"

namespace unseen {
namespace {

// The twist taking pose `a` to pose `b` under (4.7).
Vector6d TwistBetween(const Rigid3d& a, const Rigid3d& b) {
  Vector6d twist;
  twist.head<3>() = b.translation() - a.translation();
  twist.tail<3>() = LogSO3(b.rotation() * a.rotation().inverse());
  return twist;
}

}  // namespace

StageTimes& StageTimes::operator+=(const StageTimes& o) {
  predict_ms += o.predict_ms;
  render_ms += o.render_ms;
  preprocess_ms += o.preprocess_ms;
  select_ms += o.select_ms;
  solve_ms += o.solve_ms;
  total_ms += o.total_ms;
  return *this;
}

std::string SolveSummary::BriefReport() const {
  std::string iters;
  for (int l = num_levels - 1; l >= 0; --l) {
    iters += fmt::format("{}{}", iters.empty() ? "" : "/", iterations_per_level[l]);
  }
  return fmt::format(
      "levels {} iters {} renders {} re-solves {} | px cand {} grad- {} occ- {}/{}/{} undir- {} flow- {} "
      "block- {} (hidden {}) used {} (share {:.2f} block {:.2f}) | res {:.3f}->{:.3f} px, last upd {:.3f} "
      "px, corr {:.1f} px{}{}{} | ms pred {:.3f} rend {:.3f} pre {:.3f} sel {:.3f} solve {:.3f} "
      "total {:.3f}",
      num_levels, iters, renders, resamples, counts.candidates, counts.rejected_gradient,
      counts.rejected_input_gradient, counts.rejected_direction, counts.rejected_magnitude,
      counts.rejected_undirected, counts.rejected_normal_flow, counts.rejected_block,
      counts.occluded_gradient, counts.used,
      share, counts.BlockShare(),
      initial_residual_px, final_residual_px, last_update_px, correction_px,
      search_candidates
          ? fmt::format(", searched {} chose {}", search_candidates, search_choice)
          : std::string(),
      depth_counts.sampled
          ? fmt::format(" | depth used {} agree {}/{} hidden {} res {:.1f} mm", depth_counts.used,
                        depth_counts.agreeing, depth_counts.measured, depth_counts.hidden,
                        1e3 * depth_residual_m)
          : std::string(),
      region_counts.lines
          ? fmt::format(" | region lines {} used {} occluded {} overrun {} agree {:.2f} res {:.2f}",
                        region_counts.lines, region_counts.used, region_counts.occluded,
                        region_counts.overrun, region_counts.Agreement(), region_residual)
          : std::string(),
      times.predict_ms, times.render_ms, times.preprocess_ms, times.select_ms, times.solve_ms,
      times.total_ms);
}

std::string TrackResult::BriefReport() const {
  return fmt::format("{} conf {:.2f} {} | {}", ToString(status), confidence,
                     world_from_obj.ToString(), summary.BriefReport());
}

PoseRecord TrackResult::ToPoseRecord(int frame, double time_s,
                                     std::optional<double> process_ms) const {
  PoseRecord record;
  record.frame = frame;
  record.time_s = time_s;
  record.status = status;
  record.confidence = confidence;
  record.world_from_obj = world_from_obj;
  record.process_ms = process_ms;
  return record;
}

// Buffers of one camera, reused from frame to frame.
struct Tracker::CameraWork {
  bool active = false;
  PinholeCamera camera;  // level camera
  PixelRect roi;         // level pixels
  cv::Mat input_roi, region, depth_used;
  VirtualImage virtual_image;
  PreprocessedImage input_pre, virtual_pre;
  bool virtual_ok = false;  // the last PrepareVirtual rendered something
  bool input_stale = false; // input_roi changed since input_pre was computed
  // This camera's share of the current alignment; the input's pre-processing apart, as it
  // may run beside the virtual image's.
  StageTimes times;
  double input_preprocess_ms = 0.0;
};

Tracker::Tracker(const Rig& rig, Mesh model, const TrackerOptions& options)
    : rig_(rig), options_(options) {
  rig_.Check();
  options_.Check();
  for (const RigCamera& c : rig_.cameras) {
    cam_from_world_.push_back(c.cam_from_world());
    work_.push_back(std::make_unique<CameraWork>());
  }
  photometric_ = PhotometricModality(options_.selection, options_.pyramid.resample_margin_px);
  depth_ = DepthModality(options_.depth);
  region_ = RegionModality(options_.region, rig_.size());
  predictor_ = MakeMotionPredictor(options_.predictor);
  if (options_.threads != 1) pool_ = std::make_unique<ThreadPool>(options_.threads);
  SetModel(std::move(model));
}

void Tracker::RunParallel(int n, const std::function<void(int)>& fn) {
  if (pool_) {
    pool_->ParallelFor(n, fn);
  } else {
    for (int i = 0; i < n; ++i) fn(i);
  }
}

Tracker::~Tracker() = default;

void Tracker::SetModel(Mesh model) {
  model.Check("tracker model");
  if (options_.simplify.enabled) {
    SimplifyStats stats;
    model = SimplifyFlatPatches(model, options_.simplify, &stats);
    if (stats.output_triangles < stats.input_triangles) {
      UNSEEN_LOG_INFO("tracker: model's flat patches simplified, {} -> {} triangles",
                      stats.input_triangles, stats.output_triangles);
    }
  }
  Eigen::Vector3f centre;
  float radius = 0.0f;
  model.BoundingSphere(&centre, &radius);
  UNSEEN_CHECK(radius > 0.0f && std::isfinite(radius),
               "tracker model: bounding-sphere radius {} m must be positive", radius);
  sphere_centre_ = centre.cast<double>();
  sphere_radius_ = radius;
  // Corners of the model's axis-aligned box, object frame.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const Eigen::Vector3f& v : model.vertices) {
    lo = lo.cwiseMin(v.cast<double>());
    hi = hi.cwiseMax(v.cast<double>());
  }
  for (int k = 0; k < 8; ++k) {
    box_corners_[k] = Eigen::Vector3d(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(),
                                      k & 4 ? hi.z() : lo.z());
  }
  PrepareForRendering(model);
  given_model_ = std::make_shared<const Mesh>(std::move(model));
  StartWithGivenModel();
  reacquisition_.reset();
  // What was learnt about the old model's fit (its residual floor, the search's caches) does
  // not hold for the new one. The colour statistics are the object's and its
  // surroundings', not the model's: they stay.
  residual_reference_px_ = 0.0;
  region_residual_reference_ = 0.0;
  area_reference_px_ = 0.0;
  share_reference_ = 0.0;
}

Reacquisition& Tracker::Reacquirer() {
  if (!reacquisition_) reacquisition_ = std::make_unique<Reacquisition>(this);
  return *reacquisition_;
}

std::optional<PixelRect> Tracker::ObjectRect(const PinholeCamera& camera,
                                             const Rigid3d& cam_from_obj) const {
  const std::optional<PixelRect> sphere =
      camera.SphereRect(cam_from_obj * sphere_centre_, sphere_radius_);
  if (!sphere) return std::nullopt;
  std::array<Eigen::Vector3d, 8> corners;
  for (int k = 0; k < 8; ++k) corners[k] = cam_from_obj * box_corners_[k];
  const std::optional<PixelRect> box = camera.PointsRect(corners);
  if (!box) return sphere;  // a corner behind the camera: the sphere's rectangle
  const PixelRect both = box->Intersect(*sphere);
  if (both.empty()) return std::nullopt;
  return both;
}

void Tracker::Initialize(const Rigid3d& world_from_obj) {
  UNSEEN_CHECK(world_from_obj.IsValid(), "Tracker: initial pose {} is not a valid finite pose",
               world_from_obj.ToString());
  predictor_->Reset(world_from_obj);
  last_good_ = world_from_obj;
  status_ = TrackStatus::kTracking;
  bad_frames_ = 0;
  recent_correction_px_ = std::numeric_limits<double>::infinity();
  finest_level_ = 0;
  residual_reference_px_ = 0.0;
  region_residual_reference_ = 0.0;
  area_reference_px_ = 0.0;
  share_reference_ = 0.0;
  region_.Reset();
  StartWithGivenModel();
  learn_from_start_ = true;
  initialized_ = true;
}

int Tracker::NumLevelsFor(const Rigid3d& world_from_obj) const {
  double diameter_px = 0.0;
  const Eigen::Vector3d centre_world = world_from_obj * sphere_centre_;
  for (int c = 0; c < rig_.size(); ++c) {
    const Eigen::Vector3d p = cam_from_world_[c] * centre_world;
    if (p.z() <= sphere_radius_) continue;
    const PinholeCamera& cam = rig_.cameras[c].intrinsics;
    diameter_px = std::max(diameter_px, 2.0 * sphere_radius_ * std::max(cam.fx, cam.fy) / p.z());
  }
  if (diameter_px <= options_.pyramid.min_object_px) return 1;
  const int levels = 1 + static_cast<int>(std::floor(std::log2(diameter_px /
                                                               options_.pyramid.min_object_px)));
  return std::clamp(levels, 1, options_.pyramid.max_levels);
}

int Tracker::FinestLevelFor(const Rigid3d& world_from_obj) const {
  const PyramidOptions& po = options_.pyramid;
  if (po.max_finest_px <= 0.0) return 0;
  // The largest share of an image the object's rectangle covers, level-0 pixels.
  double area_px = 0.0;
  for (int c = 0; c < rig_.size(); ++c) {
    const PinholeCamera& cam = rig_.cameras[c].intrinsics;
    const std::optional<PixelRect> rect = ObjectRect(cam, cam_from_world_[c] * world_from_obj);
    if (!rect) continue;
    const PixelRect in_image = rect->Intersect(LevelRect(cam.width, cam.height, 0));
    if (in_image.empty()) continue;
    area_px = std::max(area_px, double(in_image.width()) * double(in_image.height()));
  }
  int level = 0;
  while (level + 1 < po.max_levels && area_px / double(1 << (2 * level)) > po.max_finest_px) {
    ++level;
  }
  // Back to a finer level only once the object fits it with room to spare: no switching
  // back and forth from frame to frame at the budget's edge.
  if (level < finest_level_ &&
      area_px / double(1 << (2 * level)) > po.finest_hysteresis * po.max_finest_px) {
    level = std::min(finest_level_, level + 1);
  }
  return level;
}

double Tracker::UpdatePixels(const Rigid3d& world_from_obj, const Vector6d& twist,
                             int level) const {
  // Bound on the image motion of the bounding sphere: lateral translation moves it by
  // f v / z, translation along the optical axis by about f r v / z^2, rotation by f r w / z.
  const Eigen::Vector3d centre_world = world_from_obj * sphere_centre_;
  const double rotation = twist.tail<3>().norm() * sphere_radius_;
  double px = 0.0;
  for (int c = 0; c < rig_.size(); ++c) {
    const Eigen::Vector3d p = cam_from_world_[c] * centre_world;
    const double z = p.z();
    if (z <= 0.5 * sphere_radius_) continue;
    const Eigen::Vector3d v = cam_from_world_[c].rotation() * twist.head<3>();
    const double motion = std::hypot(v.x(), v.y()) + std::abs(v.z()) * sphere_radius_ / z + rotation;
    const PinholeCamera& cam = rig_.cameras[c].intrinsics;
    px = std::max(px, std::max(cam.fx, cam.fy) / double(1 << level) * motion / z);
  }
  return px;
}

Frame Tracker::CheckFrame(const Frame& frame) const {
  const std::vector<cv::Mat>& images = frame.images;
  UNSEEN_CHECK(static_cast<int>(images.size()) == rig_.size(),
               "Tracker::Track: got {} images for a rig of {} cameras", images.size(), rig_.size());
  UNSEEN_CHECK(frame.depths.empty() || static_cast<int>(frame.depths.size()) == rig_.size(),
               "Tracker::Track: got {} depth images for a rig of {} cameras", frame.depths.size(),
               rig_.size());
  Frame out;
  out.frame_id = frame.frame_id;
  out.time_s = frame.time_s;
  out.images.resize(images.size());
  for (size_t c = 0; c < images.size(); ++c) {
    const cv::Mat& im = images[c];
    const PinholeCamera& cam = rig_.cameras[c].intrinsics;
    const std::string& name = rig_.cameras[c].name;
    if (im.empty()) continue;  // no frame from this camera: it sits this one out
    UNSEEN_CHECK(im.cols == cam.width && im.rows == cam.height,
                 "Tracker::Track: image of camera '{}' is {}x{}, the camera is {}x{}", name, im.cols,
                 im.rows, cam.width, cam.height);
    if (im.type() == CV_32FC3) {
      out.images[c] = im;
    } else {
      UNSEEN_CHECK(im.type() == CV_8UC3,
                   "Tracker::Track: image of camera '{}' has type {}; expected CV_32FC3 or CV_8UC3",
                   name, im.type());
      out.images[c] = ToFloatBgr(im, "camera '" + name + "' image");
    }
  }
  if (!options_.depth.enabled) return out;
  bool any_depth = false;
  for (size_t c = 0; c < frame.depths.size(); ++c) {
    const cv::Mat& d = frame.depths[c];
    if (d.empty()) continue;
    const PinholeCamera& cam = rig_.cameras[c].intrinsics;
    const std::string& name = rig_.cameras[c].name;
    UNSEEN_CHECK(d.type() == CV_32FC1,
                 "Tracker::Track: depth of camera '{}' has type {}; expected CV_32FC1 metres", name,
                 d.type());
    UNSEEN_CHECK(d.cols == cam.width && d.rows == cam.height,
                 "Tracker::Track: depth of camera '{}' is {}x{}, the camera is {}x{}", name, d.cols,
                 d.rows, cam.width, cam.height);
    any_depth = true;
  }
  if (any_depth) out.depths = frame.depths;
  return out;
}

TrackResult Tracker::Align(const std::vector<cv::Mat>& images, const Rigid3d& world_from_obj,
                           int num_levels) {
  Frame frame;
  frame.images = images;
  return Align(frame, world_from_obj, num_levels);
}

TrackResult Tracker::Align(const Frame& frame, const Rigid3d& world_from_obj, int num_levels) {
  UNSEEN_CHECK(world_from_obj.IsValid(), "Tracker::Align: start pose {} is not valid",
               world_from_obj.ToString());
  UNSEEN_CHECK(num_levels >= 0 && num_levels <= 8, "Tracker::Align: num_levels {} not in [0, 8]",
               num_levels);
  Timer total;
  TrackResult r = AlignChecked(CheckFrame(frame), world_from_obj, num_levels);
  r.summary.times.total_ms = total.ElapsedMilliseconds();
  return r;
}

bool Tracker::CoarseLevelsWithoutDepth(const Frame& frame) const {
  return !frame.depths.empty() && !options_.depth.coarse_with_own_texture &&
         PhotometricJudges() && !learn_from_start_ &&
         model_ == given_model_ && model_->projectors.empty();
}

bool Tracker::RenderVirtual(const Rigid3d& cam_from_obj, bool supersample, int level,
                            ThreadPool* render_pool, CameraWork* work) const {
  CameraWork& w = *work;
  // The object covers no pixel outside its rectangle, so only that part of the region
  // (plus a pixel) is rendered; the margin the filters need stays input.
  PixelRect render_rect = w.roi;
  if (const std::optional<PixelRect> rect = ObjectRect(w.camera, cam_from_obj)) {
    const PixelRect tight = rect->Grow(1).Intersect(w.roi);
    if (!tight.empty()) render_rect = tight;
  }
  PreprocessOptions compose = options_.preprocess;
  if (!OutlineIsTheObjects()) compose.background_band_px = 0;
  return ComposeVirtualImage(*model_, w.camera, cam_from_obj, w.roi, render_rect, w.input_roi,
                             supersample, compose, level, render_pool, &w.virtual_image,
                             &w.times.render_ms, &w.times.preprocess_ms);
}

bool Tracker::PrepareVirtual(const Rigid3d& cam_from_obj, int level, int rim_px,
                             ThreadPool* render_pool, CameraWork* work) const {
  CameraWork& w = *work;
  const PyramidOptions& po = options_.pyramid;
  if (!RenderVirtual(cam_from_obj, level < po.supersampled_levels, level, render_pool, &w)) {
    return false;
  }
  Timer timer;
  if (use_photometric_) {
    Preprocess(w.virtual_image.composite, options_.preprocess, level, true, &w.virtual_pre);
  }
  // Mask and its rim; depth of the rim from the nearest surface.
  if (rim_px > 0) {
    const cv::Mat rim_kernel =
        cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * rim_px + 1, 2 * rim_px + 1));
    cv::dilate(w.virtual_image.mask, w.region, rim_kernel);
    w.region.setTo(kRimPixel, w.region != w.virtual_image.mask);
    cv::dilate(w.virtual_image.depth, w.depth_used, rim_kernel);
    w.virtual_image.depth.copyTo(w.depth_used, w.virtual_image.mask);
  } else {
    w.virtual_image.mask.copyTo(w.region);
    w.virtual_image.depth.copyTo(w.depth_used);
  }
  w.region.row(0).setTo(0);
  w.region.row(w.region.rows - 1).setTo(0);
  w.region.col(0).setTo(0);
  w.region.col(w.region.cols - 1).setTo(0);
  w.times.preprocess_ms += timer.ElapsedMilliseconds();
  return true;
}

TrackResult Tracker::AlignLevels(const Frame& frame, const Rigid3d& start, int finest_level,
                                 int num_levels, int max_iterations) {
  UNSEEN_CHECK(start.IsValid(), "Tracker::AlignLevels: start pose {} is not valid",
               start.ToString());
  UNSEEN_CHECK(finest_level >= 0 && num_levels >= 1 && finest_level + num_levels <= 8,
               "Tracker::AlignLevels: levels [{}, {}) not within [0, 8]", finest_level,
               finest_level + num_levels);
  UNSEEN_CHECK(max_iterations >= 1, "Tracker::AlignLevels: max_iterations {} must be >= 1",
               max_iterations);
  LevelSpan span;
  span.finest = finest_level;
  span.num_levels = num_levels;
  span.max_iterations = max_iterations;
  span.scoring = true;
  return AlignChecked(CheckFrame(frame), start, span);
}

TrackResult Tracker::AlignChecked(const Frame& frame, const Rigid3d& start, const LevelSpan& span) {
  const std::vector<cv::Mat>& images = frame.images;
  const PyramidOptions& po = options_.pyramid;
  const int ncam = rig_.size();
  TrackResult result;
  SolveSummary& s = result.summary;
  // Levels [finest, s.num_levels), coarsest first; the finest one's rows are the result's.
  // A tracking alignment (from level 0) stops at the pixel budget's level; span.num_levels
  // still counts from level 0 then, and at least the budget's level runs.
  const bool budgeted = span.finest == 0 && !span.scoring;
  const int finest = budgeted ? FinestLevelFor(start) : span.finest;
  const int levels = span.num_levels > 0 ? span.num_levels : NumLevelsFor(start);
  s.num_levels = budgeted ? std::max(levels, finest + 1) : finest + levels;
  if (budgeted) finest_level_ = finest;
  // The level that stands for full resolution (iterations, stops, learning, level-0 units):
  // the budget's; a scoring span's finest level is a coarse one and keeps coarse stops.
  const int full_resolution = budgeted ? finest : 0;
  s.finest_level = full_resolution;
  s.iterations_per_level.assign(s.num_levels, 0);
  // Input around the object: what the filters need beyond the rim and, with the region
  // modality, a whole correspondence line outside the contour (a line that leaves the
  // region gives no row, and the contour's extremes are the lines that place the object).
  // The rim's photometric rows, for a frame's alignment from the predicted pose only: a
  // search's alignments start far off, where the rim compares the background estimated
  // beside a wrong outline with whatever texture lies there and swamps the texture's rows
  // (a cube found again at a proposed orientation: never, with a rim of 2 px).
  const int rim_px = OutlineIsTheObjects() && span.tracking ? po.rim_px : 0;
  int margin = static_cast<int>(std::ceil(3.0 * options_.preprocess.blur_sigma_px)) + rim_px + 2;
  if (options_.region.enabled) margin = std::max(margin, options_.region.line_px + 2);
  const bool input_gradients = options_.selection.use_occlusion_rejection;
  ResidualModel& photometric_model = photometric_.residual_model();
  photometric_model.kernel = options_.solver.kernel;
  photometric_model.kernel_width = options_.solver.kernel_width;
  photometric_model.min_scale = options_.solver.min_scale_px;
  const bool use_depth = !frame.depths.empty();
  photometric_model.weight = model_ != given_model_ ? options_.live_appearance.photometric_weight
                                                    : options_.photometric.weight;
  if (model_ == given_model_ && use_depth && !model_->projectors.empty()) {
    photometric_model.weight *= options_.photometric.projected_with_depth_ratio;
  }
  photometric_model.subordinate_ratio = 0.0;
  if (photometric_demoted_) {
    photometric_model.weight *= options_.photometric.dragged_weight;
    photometric_model.subordinate_ratio = options_.photometric.dragged_open_ratio;
  }
  region_.DiscardPending();
  std::vector<int> jobs;  // c: camera c's virtual image; ncam + c: its input
  for (auto& w : work_) {
    w->times = StageTimes();
    w->input_preprocess_ms = 0.0;
  }
  Rigid3d pose = start;
  std::vector<Vector6d> moved_in_cam(ncam, Vector6d::Zero());

  for (int level = s.num_levels - 1; level >= finest; --level) {
    // Region of interest (3.5): at the coarsest level the bounding sphere's rectangle,
    // whose slack around the object leaves room for the object to be found some way off;
    // at finer levels, where the pose is already close, the tighter object rectangle. Both
    // grown by the filters' margin. Placed again when the object drifts out of it.
    const bool coarsest = level == s.num_levels - 1;
    auto place_region = [&](int c, const Rigid3d& world_from_obj) {
      CameraWork& w = *work_[c];
      w.active = false;
      if (images[c].empty()) return;  // this camera has no image this frame
      const Rigid3d cam_from_obj = cam_from_world_[c] * world_from_obj;
      const std::optional<PixelRect> rect =
          coarsest ? w.camera.SphereRect(cam_from_obj * sphere_centre_, sphere_radius_)
                   : ObjectRect(w.camera, cam_from_obj);
      if (!rect) return;
      const PinholeCamera& full = rig_.cameras[c].intrinsics;
      w.roi = rect->Grow(margin).Intersect(LevelRect(full.width, full.height, level));
      if (w.roi.width() < 8 || w.roi.height() < 8) return;
      w.input_roi = DownsampledRegion(images[c], level, w.roi);
      w.input_stale = true;
      w.active = true;
    };
    Timer timer;
    for (int c = 0; c < ncam; ++c) {
      work_[c]->camera = rig_.cameras[c].intrinsics.PyramidLevel(level);
      place_region(c, pose);
    }
    s.times.preprocess_ms += timer.ElapsedMilliseconds();

    int max_iterations = level == full_resolution
                             ? po.max_iterations_per_level
                             : std::min(po.max_iterations_per_level, po.coarse_max_iterations);
    if (span.max_iterations > 0) max_iterations = std::min(max_iterations, span.max_iterations);
    // The first frame's checks measure how far each modality pulls the given pose (the
    // appearance's drag): there the coarse levels run to the stricter stop.
    const bool texture_leads = PhotometricJudges() && !learn_from_start_;
    const double min_update_px = level == full_resolution ? po.min_update_px
                                 : texture_leads ? po.photometric_coarse_min_update_px
                                                 : po.coarse_min_update_px;
    Vector6d previous_update = Vector6d::Zero();  // the level's previous solve
    // The depth rows wait for the finest level while the model's own texture leads
    // (DepthModalityOptions::coarse_with_own_texture); a search's scoring span keeps them
    // at its own finest level, where its confidence is measured.
    const bool depth_this_level =
        use_depth && (level == finest || span.coarse_depth || !CoarseLevelsWithoutDepth(frame));
    for (int iteration = 0; iteration < max_iterations; ++iteration) {
      ++s.renders;
      const Rigid3d round_pose = pose;
      if (iteration > 0 && !coarsest) {
        timer.Restart();
        for (int c = 0; c < ncam; ++c) {
          CameraWork& w = *work_[c];
          if (!w.active) continue;
          const std::optional<PixelRect> rect =
              ObjectRect(w.camera, cam_from_world_[c] * round_pose);
          if (!rect) continue;
          const PinholeCamera& full = rig_.cameras[c].intrinsics;
          const PixelRect need =
              rect->Grow(margin - 2).Intersect(LevelRect(full.width, full.height, level));
          if (need.Intersect(w.roi) != need) place_region(c, round_pose);
        }
        s.times.preprocess_ms += timer.ElapsedMilliseconds();
      }
      // Independent jobs on the available threads: per camera, the virtual image (render
      // and its pre-processing) and, after the region was placed, the input's. A single
      // job keeps the threads for itself (the render's shading pass).
      jobs.clear();
      for (int c = 0; c < ncam; ++c) {
        if (!work_[c]->active) continue;
        jobs.push_back(c);                                   // virtual image
        if (work_[c]->input_stale && use_photometric_) {
          jobs.push_back(ncam + c);  // input
        }
      }
      const int num_jobs = static_cast<int>(jobs.size());
      ThreadPool* render_pool = num_jobs == 1 ? pool_.get() : nullptr;
      RunParallel(num_jobs, [&](int j) {
        const int c = jobs[j] % ncam;
        CameraWork& w = *work_[c];
        if (jobs[j] < ncam) {
          w.virtual_ok = PrepareVirtual(cam_from_world_[c] * round_pose, level, rim_px,
                                        render_pool, &w);
        } else {
          Timer input_timer;
          Preprocess(w.input_roi, options_.preprocess, level, input_gradients, &w.input_pre);
          w.input_stale = false;
          w.input_preprocess_ms += input_timer.ElapsedMilliseconds();
        }
      });
      // Each modality's rows, per camera: pixel selection (4.8)-(4.15), (3.6) for the
      // photometric one. The modalities keep their rows per camera and share nothing, so
      // every (camera, modality) pair is a job of its own: with one camera, the photometric
      // selection runs beside the silhouette's and the depth's rows.
      photometric_.BeginRound(ncam);
      depth_.BeginRound(ncam);
      region_.BeginRound(ncam);
      // The silhouette's lines skip the blocks the photometric selection found occluded
      // (RegionModalityOptions::skip_occluded_lines): its jobs then wait for that selection.
      enum ModalityJob { kPhotometricJob, kDepthJob, kRegionJob, kModalityJobs };
      const bool region_waits = options_.region.enabled && use_photometric_ &&
                                options_.region.skip_occluded_lines &&
                                options_.selection.use_occlusion_rejection &&
                                options_.selection.block_min_share_ratio > 0.0;
      jobs.clear();
      std::vector<int> later_jobs;
      for (int c = 0; c < ncam; ++c) {
        const CameraWork& w = *work_[c];
        if (!w.active || !w.virtual_ok) continue;
        if (use_photometric_) jobs.push_back(kModalityJobs * c + kPhotometricJob);
        if (depth_this_level && !frame.depths[c].empty()) {
          jobs.push_back(kModalityJobs * c + kDepthJob);
        }
        if (options_.region.enabled) {
          (region_waits ? later_jobs : jobs).push_back(kModalityJobs * c + kRegionJob);
        }
      }
      const size_t first_later_job = jobs.size();
      jobs.insert(jobs.end(), later_jobs.begin(), later_jobs.end());
      std::vector<double> job_ms(jobs.size(), 0.0);
      auto run_modality_job = [&](int j) {
        const int c = jobs[j] / kModalityJobs;
        CameraWork& w = *work_[c];
        Timer select_timer;
        ModalityRound round;
        round.camera = c;
        round.level = level;
        round.roi = w.roi;
        round.level_camera = w.camera;
        round.camera_intrinsics = rig_.cameras[c].intrinsics;
        round.world_from_cam_rotation = rig_.cameras[c].world_from_cam.RotationMatrix();
        round.origin_in_cam = (cam_from_world_[c] * round_pose).translation();
        round.virtual_image = &w.virtual_image;
        round.input = &w.input_roi;
        round.virtual_pre = &w.virtual_pre;
        round.input_pre = &w.input_pre;
        round.photometric_region = &w.region;
        round.photometric_depth = &w.depth_used;
        if (use_depth && !frame.depths[c].empty()) round.measured_depth = &frame.depths[c];
        round.learn = level == full_resolution && !span.scoring;
        round.first_frame = learn_from_start_;
        round.without_texture = !use_photometric_ && span.tracking;
        switch (jobs[j] % kModalityJobs) {
          case kPhotometricJob:
            photometric_.AddEquations(round);
            break;
          case kDepthJob:
            depth_.AddEquations(round);
            break;
          default:
            if (region_waits) {
              round.occluded_blocks = photometric_.occluded_blocks(c);
              round.occluded_block_px = photometric_.block_px();
            }
            region_.AddEquations(round);
        }
        job_ms[j] = select_timer.ElapsedMilliseconds();
      };
      RunParallel(static_cast<int>(first_later_job), run_modality_job);
      RunParallel(static_cast<int>(jobs.size() - first_later_job),
                  [&](int j) { run_modality_job(static_cast<int>(first_later_job) + j); });
      for (size_t j = 0; j < jobs.size(); ++j) {
        work_[jobs[j] / kModalityJobs]->times.select_ms += job_ms[j];
      }
      const SelectionCounts counts = photometric_.counts();
      const RegionCounts region_counts = region_.counts();

      timer.Restart();
      const FlowSolution solution = SolveJoint(
          {&photometric_.equations(), &depth_.equations(), &region_.equations()}, options_.solver);
      if (coarsest && iteration == 0) s.start_region_counts += region_counts;
      if (level == finest) {
        // The object's whole on-screen area: an object partly past the image border is as
        // large as before, only partly out of view (FailureOptions::min_area_ratio).
        s.object_px = 0.0;
        for (int c = 0; c < ncam; ++c) {
          const CameraWork& w = *work_[c];
          if (!w.active || !w.virtual_ok) continue;
          const double min_share = options_.failure.min_in_image_share;
          const double in_image =
              min_share < 1.0
                  ? SilhouetteShareInImage(*model_, w.camera, cam_from_world_[c] * round_pose,
                                           box_corners_)
                  : 1.0;
          s.object_px += cv::countNonZero(w.virtual_image.mask) / std::max(in_image, min_share);
        }
        s.object_px *= double(1 << (2 * full_resolution));  // level-0 pixels
        s.depth_counts = depth_.counts();
        s.depth_equations = solution.modalities[1].equations;
        s.depth_residual_m = solution.modalities[1].initial_rms;
        s.region_counts = region_counts;
        // Behind an occluder, or with no texture to find one, the silhouette is judged on
        // its best lines (FailureOptions::occluded_region_share).
        const double region_share = options_.failure.occluded_region_share;
        const bool may_be_occluded = counts.occluded_gradient > 0 || !use_photometric_;
        s.region_residual = may_be_occluded && region_share < 1.0
                                ? region_.equations().TrimmedRms(region_share)
                                : solution.modalities[2].initial_rms;
        s.counts = counts;
        s.equations = solution.equations;
        s.initial_residual_px = solution.initial_rms_px;
        s.final_residual_px = solution.final_rms_px;
        s.share = counts.gradient_pixels() > 0
                      ? double(counts.used) / double(counts.gradient_pixels())
                      : 0.0;
      }
      if (!solution.ok) {
        s.times.solve_ms += timer.ElapsedMilliseconds();
        if (level == finest) s.last_update_px = std::numeric_limits<double>::infinity();
        break;
      }
      Vector6d twist = solution.twist;
      double update_px = UpdatePixels(pose, twist, level);
      if (update_px > po.max_step_px) {
        twist *= po.max_step_px / update_px;
        update_px = po.max_step_px;
      }
      pose = ApplyTwist(pose, twist);
      UNSEEN_LOG_DEBUG("level {} iteration {}: {} equations, rms {:.3f}->{:.3f} px, update {:.3f} px, "
                       "twist [{:.5f} {:.5f} {:.5f} | {:.5f} {:.5f} {:.5f}]",
                       level, iteration, solution.equations, solution.initial_rms_px,
                       solution.final_rms_px, update_px, twist(0), twist(1), twist(2), twist(3),
                       twist(4), twist(5));
      ++s.iterations_per_level[level];
      if (level == finest) s.last_update_px = update_px;
      // Done when the update is small; a tracked frame's coarse level, which only has to
      // bring the pose within the next level's reach, also when the solves swing about
      // their optimum: the update turns back on the previous one and is smaller than the
      // solve's own noise would typically make it (PyramidOptions::noise_stop_chi2), both
      // measured with the normal matrix.
      const bool swings = span.tracking && level != full_resolution &&
                          SwingsWithinNoise(previous_update, solution.twist, solution.information,
                                            po.noise_stop_chi2);
      previous_update = solution.twist;
      if (swings && update_px >= min_update_px) ++s.noise_stops;
      if (update_px < min_update_px || swings) {
        s.times.solve_ms += timer.ElapsedMilliseconds();
        break;
      }
      // Solve this round's rows again at the moved pose, measuring the input anew
      // (Modality::MoveBy), instead of rendering: most of a round's correction for a
      // fraction of its cost. The level ends when the round's rows, so re-solved, moved the
      // object little; else the next round renders at the new pose.
      // Only at the finest level: at the coarse ones, whose few rows lie mostly near the
      // silhouette, re-solves drifted (photometric alone lost the held-out spider at once).
      // The last round of a level does not re-solve: what it would move would not be
      // judged by a render; nor do re-solves go on once they stop shrinking.
      Vector6d moved = twist;  // since this round's render
      const int resolves =
          level == finest && iteration + 1 < max_iterations ? po.resample_iterations : 0;
      for (int k = 0; k < resolves && update_px >= min_update_px; ++k) {
        for (int c = 0; c < ncam; ++c) {
          const Eigen::Matrix3d cam_from_world = cam_from_world_[c].RotationMatrix();
          moved_in_cam[c].head<3>() = cam_from_world * moved.head<3>();
          moved_in_cam[c].tail<3>() = cam_from_world * moved.tail<3>();
        }
        if (use_photometric_) photometric_.MoveBy(moved_in_cam);
        depth_.MoveBy(moved_in_cam);
        if (options_.region.enabled) region_.MoveBy(moved_in_cam);
        const FlowSolution again = SolveJoint(
            {&photometric_.equations(), &depth_.equations(), &region_.equations()}, options_.solver);
        if (!again.ok) break;
        Vector6d step = again.twist;
        const double step_px = UpdatePixels(pose, step, level);
        if (!(step_px < update_px)) break;  // not converging on these rows: render anew
        update_px = step_px;
        pose = ApplyTwist(pose, step);
        moved += step;
        ++s.resamples;
        s.last_update_px = update_px;
        UNSEEN_LOG_DEBUG("level {} iteration {} re-solve {}: update {:.3f} px", level, iteration,
                         k + 1, update_px);
      }
      s.times.solve_ms += timer.ElapsedMilliseconds();
      if (resolves > 0 && UpdatePixels(round_pose, moved, level) < po.rerender_px) {
        break;
      }
    }
  }
  for (const auto& w : work_) {
    s.times += w->times;
    s.times.preprocess_ms += w->input_preprocess_ms;
  }
  s.correction_px = UpdatePixels(start, TwistBetween(start, pose), 0);
  result.world_from_obj = pose;
  result.confidence = Confidence(s, /*with_references=*/!span.scoring);
  if (!std::isfinite(result.confidence)) result.confidence = 0.0;
  return result;
}

}  // namespace unseen
