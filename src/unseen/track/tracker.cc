// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/tracker.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "unseen/image/filters.h"
#include "unseen/image/image_io.h"
#include "unseen/track/flow_jacobian.h"
#include "unseen/track/reacquisition.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/timer.h"

namespace unseen {
namespace {

double Ramp(double value, double zero_at, double one_at) {
  const double t = (value - zero_at) / (one_at - zero_at);
  return std::clamp(t, 0.0, 1.0);
}

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
      "levels {} iters {} renders {} | px cand {} grad- {} occ- {}/{}/{} undir- {} flow- {} "
      "block- {} used {} (share {:.2f} block {:.2f}) | res {:.3f}->{:.3f} px, last upd {:.3f} "
      "px, corr {:.1f} px{} | ms pred {:.3f} rend {:.3f} pre {:.3f} sel {:.3f} solve {:.3f} "
      "total {:.3f}",
      num_levels, iters, renders, counts.candidates, counts.rejected_gradient,
      counts.rejected_input_gradient, counts.rejected_direction, counts.rejected_magnitude,
      counts.rejected_undirected, counts.rejected_normal_flow, counts.rejected_block, counts.used,
      share, counts.BlockShare(),
      initial_residual_px, final_residual_px, last_update_px, correction_px,
      search_candidates ? fmt::format(", searched {}", search_candidates) : std::string(),
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
  cv::Mat input_roi, composite, region, depth_used;
  cv::Mat mask, depth, coverage;  // virtual image's mask (any coverage), depth, 2x2 count
  PreprocessedImage input_pre, virtual_pre;
  RenderBuffers render;
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
  model_ = std::make_shared<const Mesh>(std::move(model));
  reacquisition_.reset();
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
  residual_reference_px_ = 0.0;
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

std::vector<cv::Mat> Tracker::CheckImages(const std::vector<cv::Mat>& images) const {
  UNSEEN_CHECK(static_cast<int>(images.size()) == rig_.size(),
               "Tracker::Track: got {} images for a rig of {} cameras", images.size(), rig_.size());
  std::vector<cv::Mat> out(images.size());
  for (size_t c = 0; c < images.size(); ++c) {
    const cv::Mat& im = images[c];
    const PinholeCamera& cam = rig_.cameras[c].intrinsics;
    const std::string& name = rig_.cameras[c].name;
    if (im.empty()) continue;  // no frame from this camera: it sits this one out
    UNSEEN_CHECK(im.cols == cam.width && im.rows == cam.height,
                 "Tracker::Track: image of camera '{}' is {}x{}, the camera is {}x{}", name, im.cols,
                 im.rows, cam.width, cam.height);
    if (im.type() == CV_32FC3) {
      out[c] = im;
    } else {
      UNSEEN_CHECK(im.type() == CV_8UC3,
                   "Tracker::Track: image of camera '{}' has type {}; expected CV_32FC3 or CV_8UC3",
                   name, im.type());
      out[c] = ToFloatBgr(im, "camera '" + name + "' image");
    }
  }
  return out;
}

double Tracker::Confidence(const SolveSummary& s) const {
  const FailureOptions& f = options_.failure;
  if (s.equations < f.min_pixels || s.counts.gradient_pixels() <= 0) return 0.0;
  const double support_term = std::max(Ramp(s.share, f.min_share, f.good_share),
                                       Ramp(double(s.counts.used), f.min_used_px, f.good_used_px));
  double residual_term = Ramp(s.initial_residual_px, f.bad_residual_px, f.good_residual_px);
  if (residual_reference_px_ > 0.0) {
    const double reference = std::max(residual_reference_px_, f.min_reference_residual_px);
    residual_term *= Ramp(s.initial_residual_px / reference, f.bad_residual_ratio,
                          f.good_residual_ratio);
  }
  const double update_term = Ramp(s.last_update_px, f.bad_update_px, f.good_update_px);
  return support_term * residual_term * update_term;
}

TrackResult Tracker::Align(const std::vector<cv::Mat>& images, const Rigid3d& world_from_obj,
                           int num_levels) {
  UNSEEN_CHECK(world_from_obj.IsValid(), "Tracker::Align: start pose {} is not valid",
               world_from_obj.ToString());
  UNSEEN_CHECK(num_levels >= 0 && num_levels <= 8, "Tracker::Align: num_levels {} not in [0, 8]",
               num_levels);
  Timer total;
  TrackResult r = AlignChecked(CheckImages(images), world_from_obj, num_levels);
  r.summary.times.total_ms = total.ElapsedMilliseconds();
  return r;
}

void Tracker::TransferShading(int level, CameraWork* work) const {
  CameraWork& w = *work;
  // Low-pass of input and render over the fully covered pixels only (so the background
  // does not leak in); their ratio is the shading the model lacks. The ratio is formed at
  // the low-pass's coarse scale and only it is up-sampled.
  const int width = w.composite.cols, height = w.composite.rows;
  cv::Mat real(height, width, CV_32FC4), model(height, width, CV_32FC3);
  for (int y = 0; y < height; ++y) {
    const uint8_t* cov = w.coverage.ptr<uint8_t>(y);
    const float* in = w.input_roi.ptr<float>(y);
    const float* co = w.composite.ptr<float>(y);
    float* r = real.ptr<float>(y);
    float* m = model.ptr<float>(y);
    for (int x = 0; x < width; ++x) {
      const float weight = cov[x] == 4 ? 1.0f : 0.0f;
      for (int k = 0; k < 3; ++k) {
        r[4 * x + k] = weight * in[3 * x + k];
        m[3 * x + k] = weight * co[3 * x + k];
      }
      r[4 * x + 3] = weight;  // the support: share of fully covered pixels
    }
  }
  const double sigma = options_.preprocess.ShadingSigmaAtLevel(level);
  int factor = 1;
  const cv::Mat real_low = LowPassDown(real, sigma, &factor);
  const cv::Mat model_low = LowPassDown(model, sigma, &factor);
  cv::Mat gain_low(real_low.size(), CV_32FC3);
  for (int y = 0; y < gain_low.rows; ++y) {
    const float* r = real_low.ptr<float>(y);
    const float* m = model_low.ptr<float>(y);
    float* g = gain_low.ptr<float>(y);
    for (int x = 0; x < gain_low.cols; ++x) {
      const float support = r[4 * x + 3];
      for (int k = 0; k < 3; ++k) {
        const float den = m[3 * x + k];
        g[3 * x + k] = support >= 0.05f && den > 0.01f * support
                           ? std::clamp(r[4 * x + k] / den, 0.2f, 5.0f)
                           : 1.0f;
      }
    }
  }
  const cv::Mat gain = LowPassUp(gain_low, w.composite.size(), factor);
  for (int y = 0; y < height; ++y) {
    const uint8_t* cov = w.coverage.ptr<uint8_t>(y);
    const float* g = gain.ptr<float>(y);
    float* out = w.composite.ptr<float>(y);
    for (int x = 0; x < width; ++x) {
      if (!cov[x]) continue;
      for (int k = 0; k < 3; ++k) out[3 * x + k] *= g[3 * x + k];
    }
  }
}

bool Tracker::RenderVirtual(const Rigid3d& cam_from_obj, bool supersample, int level,
                            ThreadPool* render_pool, CameraWork* work) const {
  CameraWork& w = *work;
  StageTimes* times = &w.times;
  RenderOptions render_options;
  render_options.pool = render_pool;
  Timer timer;
  const int width = w.roi.width(), height = w.roi.height();
  // The object covers no pixel outside its rectangle, so only that part of the region
  // (plus a pixel) is rendered; the margin the filters need stays input.
  PixelRect rr = w.roi;
  if (const std::optional<PixelRect> rect = ObjectRect(w.camera, cam_from_obj)) {
    const PixelRect tight = rect->Grow(1).Intersect(w.roi);
    if (!tight.empty()) rr = tight;
  }
  const int ox = rr.x0 - w.roi.x0, oy = rr.y0 - w.roi.y0;
  const int rw = rr.width(), rh = rr.height();
  if (!supersample) {
    Render(*model_, w.camera, cam_from_obj, rr, render_options, &w.render);
    times->render_ms += timer.ElapsedMilliseconds();
    if (w.render.mask.rows != rh || w.render.mask.cols != rw) return false;
    // Virtual image = input with the render pasted over it (3.1 step 2).
    timer.Restart();
    const cv::Rect sub(ox, oy, rw, rh);
    w.input_roi.copyTo(w.composite);
    w.render.color.copyTo(w.composite(sub), w.render.mask);
    w.mask.create(height, width, CV_8UC1);
    w.mask.setTo(0);
    w.render.mask.copyTo(w.mask(sub));
    w.depth.create(height, width, CV_32FC1);
    w.depth.setTo(0.0f);
    w.render.depth.copyTo(w.depth(sub));
    if (options_.preprocess.shading_transfer) {
      w.coverage.create(height, width, CV_8UC1);
      w.coverage.setTo(0);
      w.coverage.setTo(4, w.mask);
      TransferShading(level, &w);
    }
    times->preprocess_ms += timer.ElapsedMilliseconds();
    return true;
  }
  const PinholeCamera fine = w.camera.Scaled(0.5);
  const PixelRect fine_roi{2 * rr.x0, 2 * rr.y0, 2 * rr.x1, 2 * rr.y1};
  Render(*model_, fine, cam_from_obj, fine_roi, render_options, &w.render);
  times->render_ms += timer.ElapsedMilliseconds();
  if (w.render.mask.rows != 2 * rh || w.render.mask.cols != 2 * rw) return false;

  // Area-average the 2x2 samples: premultiplied colour, coverage, mean depth of the
  // covered samples. Where coverage is partial, the part not covered shows the background
  // estimated from the neighbouring uncovered pixels of the input (at the true pose the
  // input's own pixel there already mixes in the object, which would bias the silhouette).
  timer.Restart();
  w.composite.create(height, width, CV_32FC3);
  w.mask.create(height, width, CV_8UC1);
  w.depth.create(height, width, CV_32FC1);
  w.coverage.create(height, width, CV_8UC1);
  for (int y = 0; y < height; ++y) {
    const float* in = w.input_roi.ptr<float>(y);
    float* out = w.composite.ptr<float>(y);
    uint8_t* mask = w.mask.ptr<uint8_t>(y);
    uint8_t* cov = w.coverage.ptr<uint8_t>(y);
    float* depth = w.depth.ptr<float>(y);
    const bool row_rendered = y >= oy && y < oy + rh;
    const int x_begin = row_rendered ? ox : width, x_end = row_rendered ? ox + rw : width;
    // Outside the rendered rectangle: no coverage, the input shows.
    for (int x = 0; x < width; ++x) {
      if (x >= x_begin && x < x_end) continue;
      cov[x] = 0;
      mask[x] = 0;
      depth[x] = 0.0f;
      for (int k = 0; k < 3; ++k) out[3 * x + k] = in[3 * x + k];
    }
    if (!row_rendered) continue;
    const int ry = y - oy;
    const uint8_t* m0 = w.render.mask.ptr<uint8_t>(2 * ry);
    const uint8_t* m1 = w.render.mask.ptr<uint8_t>(2 * ry + 1);
    const float* d0 = w.render.depth.ptr<float>(2 * ry);
    const float* d1 = w.render.depth.ptr<float>(2 * ry + 1);
    const float* c0 = w.render.color.ptr<float>(2 * ry);
    const float* c1 = w.render.color.ptr<float>(2 * ry + 1);
    for (int x = x_begin; x < x_end; ++x) {
      const int a = 2 * (x - ox), b = a + 1;
      const int n = (m0[a] != 0) + (m0[b] != 0) + (m1[a] != 0) + (m1[b] != 0);
      cov[x] = static_cast<uint8_t>(n);
      mask[x] = n ? 255 : 0;
      if (n == 0) {
        depth[x] = 0.0f;
        for (int k = 0; k < 3; ++k) out[3 * x + k] = in[3 * x + k];
        continue;
      }
      depth[x] = (d0[a] + d0[b] + d1[a] + d1[b]) / float(n);
      for (int k = 0; k < 3; ++k) {
        out[3 * x + k] = 0.25f * (c0[3 * a + k] + c0[3 * b + k] + c1[3 * a + k] + c1[3 * b + k]);
      }
    }
  }
  if (options_.preprocess.shading_transfer) TransferShading(level, &w);
  const float gamma = static_cast<float>(options_.preprocess.silhouette_gamma);
  for (int y = 0; y < height; ++y) {
    const uint8_t* cov = w.coverage.ptr<uint8_t>(y);
    float* out = w.composite.ptr<float>(y);
    for (int x = 0; x < width; ++x) {
      const int n = cov[x];
      if (n == 0 || n == 4) continue;
      float bg[3] = {0, 0, 0};
      int count = 0;
      for (int dy = -1; dy <= 1; ++dy) {
        const int yy = y + dy;
        if (yy < 0 || yy >= height) continue;
        const uint8_t* cr = w.coverage.ptr<uint8_t>(yy);
        const float* ir = w.input_roi.ptr<float>(yy);
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = x + dx;
          if (xx < 0 || xx >= width || cr[xx] != 0) continue;
          for (int k = 0; k < 3; ++k) bg[k] += ir[3 * xx + k];
          ++count;
        }
      }
      const float* in = w.input_roi.ptr<float>(y);
      const float alpha = 0.25f * n;
      for (int k = 0; k < 3; ++k) {
        const float back = count ? bg[k] / float(count) : in[3 * x + k];
        if (gamma == 1.0f) {
          out[3 * x + k] += (1.0f - alpha) * back;
        } else {  // mix in linear light, as the camera's pixel integrated it
          const float object = std::max(out[3 * x + k] / alpha, 0.0f);
          const float mixed = alpha * std::pow(object, gamma) +
                              (1.0f - alpha) * std::pow(std::max(back, 0.0f), gamma);
          out[3 * x + k] = std::pow(mixed, 1.0f / gamma);
        }
      }
    }
  }
  times->preprocess_ms += timer.ElapsedMilliseconds();
  return true;
}

bool Tracker::PrepareVirtual(const Rigid3d& cam_from_obj, int level, ThreadPool* render_pool,
                             CameraWork* work) const {
  CameraWork& w = *work;
  const PyramidOptions& po = options_.pyramid;
  if (!RenderVirtual(cam_from_obj, level < po.supersampled_levels, level, render_pool, &w)) {
    return false;
  }
  Timer timer;
  Preprocess(w.composite, options_.preprocess, level, true, &w.virtual_pre);
  // Mask and its blurred rim; depth of the rim from the nearest surface.
  if (po.rim_px > 0) {
    const cv::Mat rim_kernel =
        cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * po.rim_px + 1, 2 * po.rim_px + 1));
    cv::dilate(w.mask, w.region, rim_kernel);
    cv::dilate(w.depth, w.depth_used, rim_kernel);
    w.depth.copyTo(w.depth_used, w.mask);
  } else {
    w.mask.copyTo(w.region);
    w.depth.copyTo(w.depth_used);
  }
  w.region.row(0).setTo(0);
  w.region.row(w.region.rows - 1).setTo(0);
  w.region.col(0).setTo(0);
  w.region.col(w.region.cols - 1).setTo(0);
  w.times.preprocess_ms += timer.ElapsedMilliseconds();
  return true;
}

TrackResult Tracker::AlignChecked(const std::vector<cv::Mat>& images, const Rigid3d& start,
                                  int num_levels) {
  const PyramidOptions& po = options_.pyramid;
  const int ncam = rig_.size();
  TrackResult result;
  SolveSummary& s = result.summary;
  s.num_levels = num_levels > 0 ? num_levels : NumLevelsFor(start);
  s.iterations_per_level.assign(s.num_levels, 0);
  const int margin =
      static_cast<int>(std::ceil(3.0 * options_.preprocess.blur_sigma_px)) + po.rim_px + 2;
  const bool input_gradients = options_.selection.use_occlusion_rejection;
  // Reused from frame to frame, so that the equations keep their capacity.
  std::vector<FlowEquations>& equations = equations_;
  equations.resize(ncam);
  std::vector<SelectionCounts> camera_counts(ncam);
  std::vector<int> jobs;  // c: camera c's virtual image; ncam + c: its input
  for (auto& w : work_) {
    w->times = StageTimes();
    w->input_preprocess_ms = 0.0;
  }
  Rigid3d pose = start;

  for (int level = s.num_levels - 1; level >= 0; --level) {
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

    const int max_iterations = level == 0 ? po.max_iterations_per_level
                                          : std::min(po.max_iterations_per_level,
                                                     po.coarse_max_iterations);
    const double min_update_px = level == 0 ? po.min_update_px : po.coarse_min_update_px;
    SelectionCounts counts;
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
        if (work_[c]->input_stale) jobs.push_back(ncam + c);  // input
      }
      const int num_jobs = static_cast<int>(jobs.size());
      ThreadPool* render_pool = num_jobs == 1 ? pool_.get() : nullptr;
      RunParallel(num_jobs, [&](int j) {
        const int c = jobs[j] % ncam;
        CameraWork& w = *work_[c];
        if (jobs[j] < ncam) {
          w.virtual_ok = PrepareVirtual(cam_from_world_[c] * round_pose, level, render_pool, &w);
        } else {
          Timer input_timer;
          Preprocess(w.input_roi, options_.preprocess, level, input_gradients, &w.input_pre);
          w.input_stale = false;
          w.input_preprocess_ms += input_timer.ElapsedMilliseconds();
        }
      });
      // Pixel selection (4.8)-(4.15), (3.6), per camera.
      RunParallel(ncam, [&](int c) {
        CameraWork& w = *work_[c];
        equations[c].Clear();
        camera_counts[c] = SelectionCounts();
        if (!w.active || !w.virtual_ok) return;
        Timer select_timer;
        SelectionInput in;
        in.virtual_image = &w.virtual_pre;
        in.input_image = &w.input_pre;
        in.region = &w.region;
        in.depth = &w.depth_used;
        in.roi = w.roi;
        in.camera = w.camera;
        in.origin_in_cam = (cam_from_world_[c] * round_pose).translation();
        equations[c].world_from_cam_rotation = rig_.cameras[c].world_from_cam.RotationMatrix();
        SelectPixels(in, options_.selection, &equations[c], &camera_counts[c]);
        w.times.select_ms += select_timer.ElapsedMilliseconds();
      });
      counts = SelectionCounts();
      for (const SelectionCounts& b : camera_counts) counts += b;

      timer.Restart();
      const FlowSolution solution = SolveFlow(equations, options_.solver);
      if (level == 0) {
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
        if (level == 0) s.last_update_px = std::numeric_limits<double>::infinity();
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
      if (level == 0) s.last_update_px = update_px;
      s.times.solve_ms += timer.ElapsedMilliseconds();
      if (update_px < min_update_px) break;
    }
  }
  for (const auto& w : work_) {
    s.times += w->times;
    s.times.preprocess_ms += w->input_preprocess_ms;
  }
  s.correction_px = UpdatePixels(start, TwistBetween(start, pose), 0);
  result.world_from_obj = pose;
  result.confidence = Confidence(s);
  if (!std::isfinite(result.confidence)) result.confidence = 0.0;
  return result;
}

TrackResult Tracker::AlignPredicted(const std::vector<cv::Mat>& images,
                                    const Rigid3d& predicted) {
  const PyramidOptions& po = options_.pyramid;
  const double trust = options_.reacquisition.doubtful_confidence;
  const int full = NumLevelsFor(predicted);
  int levels = full;
  if (po.adaptive_levels && status_ == TrackStatus::kTracking) {
    // Each coarser level doubles the capture range (3.3).
    const double expected_px = po.prediction_margin * recent_correction_px_;
    levels = std::min(full, po.min_adaptive_levels);
    while (levels < full && expected_px > po.capture_px * double(1 << (levels - 1))) ++levels;
  }
  TrackResult r = AlignChecked(images, predicted, levels);
  const double reach_px = po.capture_px * double(1 << (levels - 1));
  if (levels < full && (r.confidence < trust || r.summary.correction_px > 0.75 * reach_px)) {
    TrackResult with_all = AlignChecked(images, predicted, full);
    StageTimes both = r.summary.times;  // both alignments were paid for
    both += with_all.summary.times;
    if (with_all.confidence >= r.confidence) r = std::move(with_all);
    r.summary.times = both;
  }
  if (r.confidence >= trust) {
    const double decayed = std::isfinite(recent_correction_px_)
                               ? po.correction_decay * recent_correction_px_
                               : 0.0;
    recent_correction_px_ = std::max(r.summary.correction_px, decayed);
  } else {
    recent_correction_px_ = std::numeric_limits<double>::infinity();
  }
  return r;
}

TrackResult Tracker::Track(const std::vector<cv::Mat>& images_per_camera) {
  UNSEEN_CHECK(initialized_, "Tracker::Track called before Initialize()");
  Timer total;
  const std::vector<cv::Mat> images = CheckImages(images_per_camera);
  if (std::all_of(images.begin(), images.end(), [](const cv::Mat& im) { return im.empty(); })) {
    return SkipFrame();
  }
  const FailureOptions& f = options_.failure;

  Timer timer;
  const Rigid3d predicted =
      status_ == TrackStatus::kLost ? last_good_ : predictor_->Predict(options_.frame_interval_s);
  const double predict_ms = timer.ElapsedMilliseconds();

  TrackResult r = AlignPredicted(images, predicted);
  if (status_ == TrackStatus::kLost && f.search_when_lost && r.confidence < f.recover_confidence) {
    // Re-acquisition (3.9): correlation seeds, translations and rotations around the last
    // good pose, scored at the coarse levels, the best refined.
    r = Reacquirer().Search(images, last_good_, std::move(r));
  } else if (status_ == TrackStatus::kTracking && options_.reacquisition.seed_when_doubtful &&
             r.confidence < options_.reacquisition.doubtful_confidence) {
    // A doubtful frame may have moved beyond the pyramid's capture range: try the
    // correlation seed before judging it. The motion model did not bring the object
    // where the seed found it: it restarts there rather than learning the jump.
    bool from_seed = false;
    r = Reacquirer().Seed(images, predicted, std::move(r), &from_seed);
    if (from_seed) predictor_->Reset(r.world_from_obj);
  }

  if (r.confidence >= f.lost_confidence) {
    bad_frames_ = 0;
  } else {
    ++bad_frames_;
  }
  if (status_ == TrackStatus::kTracking) {
    if (bad_frames_ >= f.lost_after_frames) {
      status_ = TrackStatus::kLost;
      predictor_->Reset(last_good_);
    } else if (r.confidence >= f.lost_confidence) {
      predictor_->Correct(r.world_from_obj, r.confidence);  // weighed by the confidence
      last_good_ = r.world_from_obj;
    }
  } else if (r.confidence >= f.recover_confidence) {
    status_ = TrackStatus::kTracking;
    bad_frames_ = 0;
    predictor_->Reset(r.world_from_obj);
    last_good_ = r.world_from_obj;
  }
  // The reference residual follows the confident frames that fit about as well as it, so
  // that a drift into a worse fit does not raise it; it is kept while lost, to judge the
  // re-acquired pose by the same floor.
  const double residual = r.summary.initial_residual_px;
  if (status_ == TrackStatus::kTracking && r.confidence >= f.recover_confidence) {
    if (residual_reference_px_ <= 0.0) {
      residual_reference_px_ = residual;
    } else if (residual < f.good_residual_ratio * residual_reference_px_) {
      residual_reference_px_ += f.residual_reference_rate * (residual - residual_reference_px_);
    }
  }
  r.status = status_;
  if (status_ == TrackStatus::kLost) r.world_from_obj = last_good_;
  if (!r.world_from_obj.IsValid()) {  // never report NaN
    r.world_from_obj = last_good_;
    r.confidence = 0.0;
  }
  r.summary.times.predict_ms = predict_ms;
  r.summary.times.total_ms = total.ElapsedMilliseconds();
  return r;
}

TrackResult Tracker::SkipFrame() {
  UNSEEN_CHECK(initialized_, "Tracker::SkipFrame called before Initialize()");
  Timer total;
  if (status_ == TrackStatus::kTracking) {
    if (++bad_frames_ >= options_.failure.lost_after_frames) {
      status_ = TrackStatus::kLost;
      predictor_->Reset(last_good_);
    } else {
      predictor_->Predict(options_.frame_interval_s);  // the object moved on meanwhile
    }
    // The next frame is a frame interval further from the last correction.
    recent_correction_px_ = std::numeric_limits<double>::infinity();
  }
  TrackResult r;
  r.world_from_obj = last_good_;
  r.status = TrackStatus::kLost;
  r.confidence = 0.0;
  r.summary.times.total_ms = total.ElapsedMilliseconds();
  return r;
}

}  // namespace unseen
