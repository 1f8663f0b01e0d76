// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/reacquisition.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "unseen/image/filters.h"
#include "unseen/image/template_matching.h"
#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/timer.h"

namespace unseen {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Gradient magnitude of the LINF-normalised (4.11), blurred image, the channels combined
// in quadrature: a gain or a smooth shading of the input changes it little, and an edge
// counts whatever its polarity.
cv::Mat GradientMagnitude(const cv::Mat& bgr, const PreprocessOptions& preprocess, int level) {
  PreprocessOptions p = preprocess;
  p.use_linf = true;
  PreprocessedImage pre;
  Preprocess(bgr, p, level, true, &pre);
  cv::Mat sq = pre.gx.mul(pre.gx) + pre.gy.mul(pre.gy);
  cv::Mat sum;
  cv::transform(sq, sum, cv::Matx13f(1.0f, 1.0f, 1.0f));
  cv::sqrt(sum, sum);
  return sum;
}

// The image a template is correlated on (ReacquisitionOptions::colour_correlation): the
// gradient magnitude, or the LINF-normalised (4.11), blurred colour (three channels).
cv::Mat CorrelationFeature(const cv::Mat& bgr, bool colour, const PreprocessOptions& preprocess,
                           int level) {
  if (!colour) return GradientMagnitude(bgr, preprocess, level);
  PreprocessOptions p = preprocess;
  p.use_linf = true;
  PreprocessedImage pre;
  Preprocess(bgr, p, level, false, &pre);
  return pre.blurred;
}

// One peak of a correlation map: template top-left position (sub-pixel) and NCC.
struct Peak {
  Eigen::Vector2d position;
  double score = 0.0;
};

// Offset in (-0.5, 0.5) of the vertex of the parabola through (-1, a), (0, b), (1, c).
double ParabolaVertex(float a, float b, float c) {
  const double den = double(a) - 2.0 * double(b) + double(c);
  if (!(den < 0.0)) return 0.0;
  return std::clamp(0.5 * (double(a) - double(c)) / den, -0.5, 0.5);
}

// The `count` highest local maxima of `ncc` (CV_32FC1) at least `separation` pixels apart.
std::vector<Peak> FindPeaks(cv::Mat ncc, int count, double separation) {
  std::vector<Peak> peaks;
  cv::Mat free(ncc.size(), CV_8UC1, cv::Scalar(255));
  const int radius = std::max(1, static_cast<int>(std::ceil(separation)));
  for (int k = 0; k < count; ++k) {
    double best = 0.0;
    cv::Point at;
    cv::minMaxLoc(ncc, nullptr, &best, nullptr, &at, free);
    if (!(best > -1.0) || at.x < 0) break;
    Peak p;
    p.score = best;
    p.position = Eigen::Vector2d(at.x, at.y);
    if (at.x > 0 && at.x + 1 < ncc.cols) {
      const float* row = ncc.ptr<float>(at.y);
      p.position.x() += ParabolaVertex(row[at.x - 1], row[at.x], row[at.x + 1]);
    }
    if (at.y > 0 && at.y + 1 < ncc.rows) {
      p.position.y() += ParabolaVertex(ncc.at<float>(at.y - 1, at.x), ncc.at<float>(at.y, at.x),
                                       ncc.at<float>(at.y + 1, at.x));
    }
    peaks.push_back(p);
    cv::circle(free, at, radius, cv::Scalar(0), cv::FILLED);
  }
  return peaks;
}

// The search window of one camera at the correlation level, prepared once for every
// orientation that is matched in it.
struct CameraWindow {
  bool ok = false;
  PinholeCamera camera;  // level camera
  Rigid3d cam_from_world;
  double radius_px = 0.0;  // bounding sphere's projected radius, level px
  int half = 0;            // templates are (2 half + 1)^2 around the projected centre
  PixelRect padded;        // level pixels the feature map covers (may exceed the image)
  cv::Mat feature;         // CorrelationFeature over `padded`, 0 outside the image
  cv::Scalar fill;         // mean colour of the window (the templates' background)
  // Correlates templates with `feature`, its transforms made once for all of them.
  std::shared_ptr<const MaskedTemplateMatcher> matcher;
};

CameraWindow PrepareWindow(const cv::Mat& image, const RigCamera& rig_camera,
                           const Eigen::Vector3d& centre_in_world, double sphere_radius,
                           int level, bool colour, const ReacquisitionOptions& options,
                           const PreprocessOptions& preprocess) {
  CameraWindow w;
  if (image.empty()) return w;  // no image from this camera this frame
  const PinholeCamera& cam0 = rig_camera.intrinsics;
  w.camera = cam0.PyramidLevel(level);
  w.cam_from_world = rig_camera.cam_from_world();
  const Eigen::Vector3d centre = w.cam_from_world * centre_in_world;
  if (!(centre.z() > 1.5 * sphere_radius)) return w;  // behind or around the camera
  const Eigen::Vector2d centre_px = w.camera.Project(centre);
  w.radius_px = std::max(w.camera.fx, w.camera.fy) * sphere_radius / centre.z();
  if (!centre_px.allFinite() || w.radius_px < 2.0) return w;
  // Templates cover the projected bounding sphere, off-axis stretch and the blur's reach.
  const int pad = static_cast<int>(std::ceil(3.0 * preprocess.blur_sigma_px)) + 2;
  w.half = static_cast<int>(std::ceil(1.2 * w.radius_px)) + pad;
  const int side = 2 * w.half + 1;
  // The window: a template moved by up to search_radii radii each way, clipped to the
  // image but for half a template, so that an object half out of view can be found.
  const int reach = static_cast<int>(std::ceil(options.search_radii * w.radius_px));
  const int x0 = static_cast<int>(std::lround(centre_px.x())) - w.half - reach;
  const int y0 = static_cast<int>(std::lround(centre_px.y())) - w.half - reach;
  const PixelRect wanted{x0, y0, x0 + side + 2 * reach, y0 + side + 2 * reach};
  const PixelRect level_rect = LevelRect(cam0.width, cam0.height, level);
  const PixelRect inside = wanted.Intersect(level_rect);
  w.padded = wanted.Intersect(level_rect.Grow(w.half));
  if (inside.width() < 8 || inside.height() < 8 || w.padded.width() < side ||
      w.padded.height() < side) {
    return w;
  }
  const cv::Mat window = DownsampledRegion(image, level, inside);
  w.fill = cv::mean(window);
  cv::copyMakeBorder(CorrelationFeature(window, colour, preprocess, level), w.feature,
                     inside.y0 - w.padded.y0, w.padded.y1 - inside.y1, inside.x0 - w.padded.x0,
                     w.padded.x1 - inside.x1, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  w.matcher = std::make_shared<const MaskedTemplateMatcher>(w.feature, cv::Size(side, side));
  w.ok = true;
  return w;
}

// Colour and coverage of `model` at `cam_from_obj` in `camera`, area-averaged from a 2x2
// supersampled render; false when it covers no pixel.
bool SupersampledRender(const Mesh& model, const PinholeCamera& camera, const Rigid3d& cam_from_obj,
                        cv::Mat* color, cv::Mat* alpha) {
  const PinholeCamera fine = camera.Scaled(0.5);
  RenderBuffers buffers;
  Render(model, fine, cam_from_obj, fine.ImageRect(), RenderOptions(), &buffers);
  if (buffers.mask.empty() || cv::countNonZero(buffers.mask) == 0) return false;
  const cv::Size size(camera.width, camera.height);
  cv::resize(buffers.color, *color, size, 0, 0, cv::INTER_AREA);
  cv::Mat coverage;
  buffers.mask.convertTo(coverage, CV_32F, 1.0 / 255.0);
  cv::resize(coverage, *alpha, size, 0, 0, cv::INTER_AREA);
  return true;
}

// The model at `world_from_obj` matched in camera window `w`.
struct CameraMatch {
  bool ok = false;
  std::vector<Peak> peaks;             // template top-left positions, best first
  Eigen::Vector2d reference_position;  // template top-left where the pose puts it
  Eigen::Vector3d centre_in_cam;       // bounding-sphere centre at the pose

  Eigen::Vector2d Shift(const Peak& p) const { return p.position - reference_position; }
  // Displacement of the object in the camera frame for peak `p`, depth kept.
  Eigen::Vector3d Displacement(const CameraWindow& w, const Peak& p) const {
    const Eigen::Vector2d pixel = w.camera.Project(centre_in_cam) + Shift(p);
    return w.camera.Unproject(pixel, centre_in_cam.z()) - centre_in_cam;
  }
};

CameraMatch MatchInWindow(const CameraWindow& w, const Mesh& model,
                          const Eigen::Vector3d& sphere_centre, const Rigid3d& world_from_obj,
                          int level, int max_peaks, const PreprocessOptions& preprocess,
                          CorrelationTemplateCache* templates) {
  CameraMatch m;
  if (!w.ok) return m;
  const Rigid3d cam_from_obj = w.cam_from_world * world_from_obj;
  m.centre_in_cam = cam_from_obj * sphere_centre;
  const Eigen::Vector2d centre_px = w.camera.Project(m.centre_in_cam);
  if (!centre_px.allFinite()) return m;
  // Template: the model rendered 2x2 supersampled into a square around its centre, over
  // the window's mean colour (the real background is unknown) so that the silhouette has
  // an edge of typical contrast.
  const int side = 2 * w.half + 1;
  const int ox = static_cast<int>(std::lround(centre_px.x())) - w.half;
  const int oy = static_cast<int>(std::lround(centre_px.y())) - w.half;
  PinholeCamera template_camera = w.camera;
  template_camera.width = template_camera.height = side;
  template_camera.cx -= ox;
  template_camera.cy -= oy;
  CorrelationTemplateCache::Template uncached;
  CorrelationTemplateCache::Template& t =
      templates ? templates->Find(template_camera, cam_from_obj) : uncached;
  if (!templates) SupersampledRender(model, template_camera, cam_from_obj, &t.color, &t.coverage);
  if (t.color.empty()) return m;
  double fill_moved = 0.0;
  for (int k = 0; k < 3; ++k) fill_moved = std::max(fill_moved, std::abs(t.fill[k] - w.fill[k]));
  if (!t.prepared || !w.matcher->Fits(*t.prepared) ||
      t.prepared->centred_spectra.size() != static_cast<size_t>(w.feature.channels()) ||
      fill_moved > CorrelationTemplateCache::kFillTolerance) {
    cv::Mat composite(side, side, CV_32FC3);
    for (int y = 0; y < side; ++y) {
      const float* a = t.coverage.ptr<float>(y);
      const float* c = t.color.ptr<float>(y);
      float* out = composite.ptr<float>(y);
      for (int x = 0; x < side; ++x) {
        for (int k = 0; k < 3; ++k) {
          out[3 * x + k] = c[3 * x + k] + (1.0f - a[x]) * float(w.fill[k]);
        }
      }
    }
    const bool colour = w.feature.channels() > 1;
    const cv::Mat template_feature = CorrelationFeature(composite, colour, preprocess, level);
    // Compared over the object and its silhouette's blurred edge; the rest of the square
    // is background, unknown.
    cv::Mat mask;
    cv::compare(t.coverage, 0.0, mask, cv::CMP_GT);
    const int edge = static_cast<int>(std::ceil(preprocess.blur_sigma_px)) + 1;
    cv::dilate(mask, mask,
               cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * edge + 1, 2 * edge + 1)));
    t.prepared = w.matcher->Prepare(template_feature, mask);
    t.fill = w.fill;
  }
  // Zero-mean normalised within the mask; -1 over a featureless part of the window.
  m.peaks = FindPeaks(w.matcher->Match(*t.prepared), max_peaks, w.radius_px);
  for (Peak& p : m.peaks) p.position += Eigen::Vector2d(w.padded.x0, w.padded.y0);
  m.reference_position = Eigen::Vector2d(ox, oy);
  m.ok = !m.peaks.empty();
  return m;
}

}  // namespace

void CorrelationTemplateCache::Bind(std::shared_ptr<const Mesh> model) {
  UNSEEN_CHECK(model != nullptr, "CorrelationTemplateCache: no model");
  if (model != model_) entries_.clear();
  model_ = std::move(model);
}

CorrelationTemplateCache::Template& CorrelationTemplateCache::Find(const PinholeCamera& camera,
                                                                   const Rigid3d& cam_from_obj) {
  UNSEEN_CHECK(model_ != nullptr, "CorrelationTemplateCache::Find before Bind");
  auto same_camera = [&](const PinholeCamera& c) {
    return c.width == camera.width && c.height == camera.height && c.fx == camera.fx &&
           c.fy == camera.fy && c.cx == camera.cx && c.cy == camera.cy;
  };
  for (Template& e : entries_) {
    if (same_camera(e.camera) && e.cam_from_obj.translation() == cam_from_obj.translation() &&
        e.cam_from_obj.rotation().coeffs() == cam_from_obj.rotation().coeffs()) {
      ++hits_;
      return e;
    }
  }
  ++misses_;
  if (static_cast<int>(entries_.size()) >= kMaxEntries) entries_.pop_front();
  Template& e = entries_.emplace_back();
  e.camera = camera;
  e.cam_from_obj = cam_from_obj;
  // Left empty when the model covers no pixel: remembered as such.
  SupersampledRender(*model_, camera, cam_from_obj, &e.color, &e.coverage);
  return e;
}

int CorrelationLevel(double diameter_px, const ReacquisitionOptions& options) {
  if (!(diameter_px > options.seed_object_px)) return 0;
  return std::clamp(static_cast<int>(std::floor(std::log2(diameter_px / options.seed_object_px))),
                    0, 7);
}

std::vector<CorrelationSeed> FindCorrelationSeeds(
    const std::vector<cv::Mat>& images, const Rig& rig, const Mesh& model,
    const Eigen::Vector3d& sphere_centre, double sphere_radius,
    const std::vector<Rigid3d>& references, const ReacquisitionOptions& options,
    const PreprocessOptions& preprocess, CorrelationTemplateCache* templates) {
  UNSEEN_CHECK(static_cast<int>(images.size()) == rig.size(),
               "FindCorrelationSeeds: {} images for a rig of {} cameras", images.size(),
               rig.size());
  std::vector<CorrelationSeed> seeds;
  if (references.empty()) return seeds;
  // One level and one window per camera for all references, from the first; the level
  // from the camera that sees the object largest.
  const Eigen::Vector3d centre_in_world = references[0] * sphere_centre;
  double diameter_px = 0.0;
  for (const RigCamera& c : rig.cameras) {
    const Eigen::Vector3d p = c.cam_from_world() * centre_in_world;
    if (p.z() <= sphere_radius) continue;
    diameter_px = std::max(
        diameter_px, 2.0 * sphere_radius * std::max(c.intrinsics.fx, c.intrinsics.fy) / p.z());
  }
  if (diameter_px <= 0.0) return seeds;
  const int level = CorrelationLevel(diameter_px, options);
  const bool colour = options.colour_correlation && model.HasAppearance();
  std::vector<CameraWindow> windows;
  for (int c = 0; c < rig.size(); ++c) {
    windows.push_back(PrepareWindow(images[c], rig.cameras[c], centre_in_world, sphere_radius,
                                    level, colour, options, preprocess));
  }

  for (int index = 0; index < static_cast<int>(references.size()); ++index) {
    const Rigid3d& reference = references[index];
    std::vector<CameraMatch> matches;
    for (int c = 0; c < rig.size(); ++c) {
      matches.push_back(MatchInWindow(windows[c], model, sphere_centre, reference, level,
                                      options.max_seeds, preprocess, templates));
    }
    auto seed_from = [&](const std::vector<std::pair<int, const Peak*>>& used) {
      // Weighted least squares on the world displacement d: rows 0 and 1 of each
      // camera's rotation times d equal that camera's lateral displacement; a pull of
      // 1e-6 of the mean weight towards d = 0 fixes the directions no camera constrains.
      Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
      Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
      CorrelationSeed seed;
      seed.level = level;
      seed.reference_index = index;
      seed.shift_px.assign(rig.size(), Eigen::Vector2d(kNaN, kNaN));
      double weight_sum = 0.0;
      for (const auto& [c, peak] : used) {
        const CameraMatch& m = matches[c];
        const double w = std::max(peak->score, 1e-3);
        const Eigen::Vector3d d = m.Displacement(windows[c], *peak);
        const Eigen::Matrix3d rotation = windows[c].cam_from_world.RotationMatrix();
        for (int row = 0; row < 2; ++row) {
          const Eigen::Vector3d a = rotation.row(row).transpose();
          normal += w * a * a.transpose();
          rhs += w * a * d(row);
        }
        seed.shift_px[c] = m.Shift(*peak);
        seed.max_shift_px = std::max(seed.max_shift_px, seed.shift_px[c].norm());
        seed.score += w * peak->score;
        weight_sum += w;
      }
      seed.score /= weight_sum;
      normal += 1e-6 * (weight_sum / used.size()) * Eigen::Matrix3d::Identity();
      const Eigen::Vector3d displacement = normal.ldlt().solve(rhs);
      seed.world_from_obj = Rigid3d(reference.rotation(), reference.translation() + displacement);
      return seed;
    };

    std::vector<std::pair<int, const Peak*>> best;
    int strongest = -1;
    for (int c = 0; c < rig.size(); ++c) {
      if (!matches[c].ok || matches[c].peaks[0].score < options.min_correlation) continue;
      best.emplace_back(c, &matches[c].peaks[0]);
      if (strongest < 0 || matches[c].peaks[0].score > matches[strongest].peaks[0].score) {
        strongest = c;
      }
    }
    if (best.empty()) continue;
    seeds.push_back(seed_from(best));
    for (size_t k = 1; k < matches[strongest].peaks.size(); ++k) {
      const Peak& p = matches[strongest].peaks[k];
      if (p.score < options.min_correlation) break;
      seeds.push_back(seed_from({{strongest, &p}}));
    }
  }
  // Best first, ties in the order found. The order is sorted, not the seeds: libstdc++'s
  // std::stable_sort takes its buffer from get_temporary_buffer, which ignores the
  // over-alignment of Eigen members (32 bytes with AVX) and crashed AVX-512 builds.
  std::vector<int> order(seeds.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&seeds](int a, int b) { return seeds[a].score > seeds[b].score; });
  std::vector<CorrelationSeed> sorted;
  sorted.reserve(seeds.size());
  for (int i : order) sorted.push_back(std::move(seeds[i]));
  seeds = std::move(sorted);
  if (static_cast<int>(seeds.size()) > options.max_seeds) seeds.resize(options.max_seeds);
  return seeds;
}

std::vector<CorrelationSeed> FindCorrelationSeeds(const std::vector<cv::Mat>& images,
                                                  const Rig& rig, const Mesh& model,
                                                  const Eigen::Vector3d& sphere_centre,
                                                  double sphere_radius, const Rigid3d& reference,
                                                  const ReacquisitionOptions& options,
                                                  const PreprocessOptions& preprocess) {
  return FindCorrelationSeeds(images, rig, model, sphere_centre, sphere_radius,
                              std::vector<Rigid3d>{reference}, options, preprocess);
}

std::vector<Rigid3d> TurnedAboutCentre(const Rigid3d& world_from_obj,
                                       const Eigen::Vector3d& centre_in_obj, double angle_deg) {
  std::vector<Rigid3d> out;
  if (angle_deg <= 0.0) return out;
  const double angle = angle_deg * M_PI / 180.0;
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {-1.0, 1.0}) {
      out.push_back(RotatedAboutPoint(
          world_from_obj, ExpSO3(sign * angle * Eigen::Vector3d::Unit(axis)), centre_in_obj));
    }
  }
  return out;
}

Rigid3d RotatedAboutPoint(const Rigid3d& world_from_obj, const Eigen::Quaterniond& rotation,
                          const Eigen::Vector3d& centre_in_obj) {
  const Eigen::Vector3d centre = world_from_obj * centre_in_obj;
  const Eigen::Quaterniond turned = rotation * world_from_obj.rotation();
  return Rigid3d(turned, centre - turned * centre_in_obj);
}

std::vector<Rigid3d> ReacquisitionCandidates(const Rigid3d& last_good,
                                             const std::vector<CorrelationSeed>& seeds,
                                             const Eigen::Vector3d& sphere_centre,
                                             double translation_step_m,
                                             const ReacquisitionOptions& options) {
  std::vector<Rigid3d> out;
  auto add = [&](const Rigid3d& pose) {
    if (static_cast<int>(out.size()) < options.max_candidates) out.push_back(pose);
  };
  for (const CorrelationSeed& s : seeds) add(s.world_from_obj);
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {-1.0, 1.0}) {
      const Eigen::Vector3d offset =
          sign * translation_step_m * (axis == 2 ? 2.0 : 1.0) * Eigen::Vector3d::Unit(axis);
      add(Rigid3d(last_good.rotation(), last_good.translation() + offset));
    }
  }
  for (const Rigid3d& p : TurnedAboutCentre(last_good, sphere_centre, options.rotation_deg)) {
    add(p);
  }
  if (!seeds.empty()) {
    for (const Rigid3d& p :
         TurnedAboutCentre(seeds[0].world_from_obj, sphere_centre, options.rotation_deg)) {
      add(p);
    }
  }
  return out;
}

Reacquisition::Reacquisition(Tracker* tracker) : tracker_(*tracker) {
  Eigen::Vector3f centre;
  float radius = 0.0f;
  tracker_.model().BoundingSphere(&centre, &radius);
  sphere_centre_ = centre.cast<double>();
  sphere_radius_ = radius;
}

std::vector<Rigid3d> Reacquisition::Proposals(const Frame& frame, const CorrelationSeed& seed) const {
  const PoseProposer& proposer = tracker_.pose_proposer();
  const int wanted = tracker_.options().reacquisition.proposals;
  if (!proposer || wanted <= 0) return {};
  // The object's box where the seed puts it (Tracker::ObjectRect), in the camera that sees
  // it largest (the proposer takes its longer side).
  const Rig& rig = tracker_.rig();
  int camera = -1;
  PixelRect box;
  for (int c = 0; c < rig.size(); ++c) {
    if (c >= static_cast<int>(frame.images.size()) || frame.images[c].empty() ||
        !seed.shift_px[c].allFinite()) {
      continue;
    }
    const std::optional<PixelRect> rect = tracker_.ObjectRect(
        rig.cameras[c].intrinsics, rig.cameras[c].cam_from_world() * seed.world_from_obj);
    if (!rect || rect->width() < 8 || rect->height() < 8) continue;
    if (camera < 0 || rect->width() * rect->height() > box.width() * box.height()) {
      camera = c;
      box = *rect;
    }
  }
  if (camera < 0) return {};
  // Each proposal's orientation, about the object's centre where the seed puts it.
  const Eigen::Vector3d centre = seed.world_from_obj * sphere_centre_;
  std::vector<Rigid3d> out;
  for (const Rigid3d& p : proposer(frame, camera, box)) {
    if (static_cast<int>(out.size()) >= wanted) break;
    out.emplace_back(p.rotation(), centre - p.rotation() * sphere_centre_);
  }
  return out;
}

Reacquisition::~Reacquisition() = default;

TrackResult Reacquisition::AlignCoarse(const std::vector<cv::Mat>& images, int finest,
                                       int num_levels, const Rigid3d& start) {
  // Colour alone, as the correlation that found the candidates: measured depth serves the
  // full-resolution refinement.
  if (finest == 0) return tracker_.Align(images, start, num_levels);
  const TrackerOptions& options = tracker_.options();
  Frame frame;
  frame.images = images;
  return tracker_.AlignLevels(
      frame, start, finest, num_levels,
      std::min(options.pyramid.coarse_max_iterations, options.reacquisition.score_iterations));
}

TrackResult Reacquisition::ScoreCoarse(const std::vector<cv::Mat>& images,
                                       const Rigid3d& start) {
  const int levels = tracker_.NumLevelsFor(start);
  const int finest = std::max(0, levels - tracker_.options().reacquisition.score_levels);
  return AlignCoarse(images, finest, levels - finest, start);
}

ReacquisitionOptions Reacquisition::CorrelationOptions() const {
  // Colour correlates only while the model's colours are trusted: not when they were found
  // not to fit the images and the silhouette leads (their pattern then finds look-alikes as
  // readily as the object: a weakly textured duck behind a textured spider).
  ReacquisitionOptions o = tracker_.options().reacquisition;
  o.colour_correlation =
      o.colour_correlation && tracker_.photometric_in_use() && !tracker_.photometric_demoted();
  return o;
}

TrackResult Reacquisition::Search(const Frame& frame, const Rigid3d& last_good,
                                  const Rigid3d& coasted) {
  const std::vector<cv::Mat>& images = frame.images;
  const TrackerOptions& options = tracker_.options();
  const ReacquisitionOptions& o = options.reacquisition;
  StageTimes times;
  // The coasted pose is scored first: an object that comes out from behind an occluder is
  // most likely where it went on moving. When it scores at least accept_coasted_score at
  // the coarse levels, it is refined at once and, if that re-acquires the object, the
  // search ends there (no correlation, no other candidate).
  const int levels = tracker_.NumLevelsFor(last_good);
  const int finest = std::max(0, levels - o.score_levels);
  TrackResult coasted_scored = AlignCoarse(images, finest, levels - finest, coasted);
  times += coasted_scored.summary.times;
  if (finest > 0 && coasted_scored.world_from_obj.IsValid() &&
      coasted_scored.confidence >= o.accept_coasted_score) {
    TrackResult r = tracker_.Align(frame, coasted_scored.world_from_obj, levels);
    times += r.summary.times;
    UNSEEN_LOG_DEBUG("coasted pose: coarse conf {:.2f}, refined conf {:.2f} at {}",
                     coasted_scored.confidence, r.confidence, r.world_from_obj.ToString());
    if (r.world_from_obj.IsValid() && r.confidence >= options.failure.recover_confidence) {
      r.summary.times = times;
      r.summary.search_candidates = 1;
      r.summary.search_choice = 0;
      return r;
    }
  }
  Timer timer;
  std::vector<CorrelationSeed> seeds;
  if (o.use_correlation) {
    // The last good pose and its rotations, each located by correlation.
    std::vector<Rigid3d> orientations{last_good};
    for (const Rigid3d& p : TurnedAboutCentre(last_good, sphere_centre_, o.rotation_deg)) {
      orientations.push_back(p);
    }
    // The same last good pose in every lost frame: its templates are rendered once.
    templates_.Bind(tracker_.shared_model());
    seeds = FindCorrelationSeeds(images, tracker_.rig(), templates_.model(), sphere_centre_,
                                 sphere_radius_, orientations, CorrelationOptions(),
                                 options.preprocess, &templates_);
  }
  const double correlation_ms = timer.ElapsedMilliseconds();
  times.preprocess_ms += correlation_ms;
  UNSEEN_LOG_DEBUG("correlation: {} seeds in {:.1f} ms (template renders reused {}, made {})",
                   seeds.size(), correlation_ms, templates_.hits(), templates_.misses());
  for (const CorrelationSeed& seed : seeds) {
    UNSEEN_LOG_DEBUG("correlation seed: shift {:.1f} px at level {}, ncc {:.2f}: {}",
                     seed.max_shift_px, seed.level, seed.score, seed.world_from_obj.ToString());
  }
  // The coasted pose first: an object that comes out from behind an occluder is most
  // likely where it went on moving.
  std::vector<Rigid3d> candidates{coasted};
  // Then the coasted turn with the object's centre held where it was last seen: a hand
  // that turns an object behind an occluder goes on turning it, while the extrapolated
  // translation (weakest in depth, and learnt from the fading frames before the loss) may
  // run away. Not when the two are a fraction of a search step apart.
  const double step_m = options.failure.search_offset * sphere_radius_;
  if (o.turn_in_place) {
    const Rigid3d turned = RotatedAboutPoint(
        last_good, coasted.rotation() * last_good.rotation().inverse(), sphere_centre_);
    if ((turned.translation() - coasted.translation()).norm() > 0.25 * step_m) {
      candidates.push_back(turned);
    }
  }
  const std::vector<Rigid3d> around =
      ReacquisitionCandidates(last_good, seeds, sphere_centre_, step_m, o);
  // A new loss (another last good pose) starts with a complete search.
  if (!quiet_last_good_ || !(quiet_last_good_->translation() == last_good.translation() &&
                             quiet_last_good_->rotation().coeffs() ==
                                 last_good.rotation().coeffs())) {
    quiet_ = false;
    quiet_slice_ = 0;
  }
  quiet_last_good_ = last_good;
  const int num_seeds = std::min(static_cast<int>(seeds.size()), static_cast<int>(around.size()));
  const int num_others = static_cast<int>(around.size()) - num_seeds;
  // The seeds, the proposer's orientations at the best of them, then the others.
  candidates.insert(candidates.end(), around.begin(), around.begin() + num_seeds);
  if (!seeds.empty()) {
    const std::vector<Rigid3d> proposed = Proposals(frame, seeds[0]);
    candidates.insert(candidates.end(), proposed.begin(), proposed.end());
  }
  if (quiet_ && o.quiet_candidates >= 0 && o.quiet_candidates < num_others) {
    // The object was not seen in the last search: a slice of the others.
    for (int k = 0; k < o.quiet_candidates; ++k) {
      candidates.push_back(around[num_seeds + (quiet_slice_ * o.quiet_candidates + k) % num_others]);
    }
    ++quiet_slice_;
  } else {
    candidates.insert(candidates.end(), around.begin() + num_seeds, around.end());
  }

  // Score every candidate at the coarse levels (the full pyramid when it has no more); the
  // coasted pose's score is the one above.
  struct Scored {
    double score;
    Rigid3d pose;
    int order;
  };
  std::vector<Scored> scored;
  TrackResult best;  // nothing found yet
  best.world_from_obj = coasted;
  int choice = -1;  // the candidate `best` came from
  for (int i = 0; i < static_cast<int>(candidates.size()); ++i) {
    TrackResult c = i == 0 ? std::move(coasted_scored)
                           : AlignCoarse(images, finest, levels - finest, candidates[i]);
    if (i > 0) times += c.summary.times;
    if (!c.world_from_obj.IsValid()) continue;
    if (finest == 0) {  // already aligned at full resolution
      if (c.confidence > best.confidence) {
        best = std::move(c);
        choice = i;
      }
      continue;
    }
    UNSEEN_LOG_DEBUG("candidate {}: coarse conf {:.2f} at {}", i, c.confidence,
                     c.world_from_obj.ToString());
    scored.push_back({c.confidence, c.world_from_obj, i});
  }
  auto by_score = [](const Scored& a, const Scored& b) {
    return a.score != b.score ? a.score > b.score : a.order < b.order;
  };
  std::sort(scored.begin(), scored.end(), by_score);
  // Nothing like the object at any candidate: the next search, if the object stays lost,
  // is a quiet one.
  quiet_ = finest == 0 ? best.confidence < o.min_score
                       : scored.empty() || scored.front().score < o.min_score;
  // Aligns candidate `c` on from where it stopped (`num_levels` from `level`); false (the
  // candidate as it was) when that gave no valid pose.
  auto continue_one = [&](Scored* c, int level, int num_levels) {
    TrackResult r = AlignCoarse(images, level, num_levels, c->pose);
    times += r.summary.times;
    UNSEEN_LOG_DEBUG("candidate {} at level {}: conf {:.2f} at {}", c->order, level, r.confidence,
                     r.world_from_obj.ToString());
    if (!r.world_from_obj.IsValid()) return false;
    c->score = r.confidence;
    c->pose = r.world_from_obj;
    return true;
  };
  // The same for every scored candidate, sorted again.
  auto continue_scored = [&](int level, int num_levels) {
    for (Scored& c : scored) continue_one(&c, level, num_levels);
    std::sort(scored.begin(), scored.end(), by_score);
  };
  // Successive halving in rounds at the scoring level: each candidate had score_iterations
  // rounds; the better half, at least refine_candidates, as many more from where they
  // stopped, and so on up to the coarse levels' own limit. A candidate that needs a long
  // way (a turn the candidates missed) is continued while it looks promising; the hopeless
  // stop early.
  const int round_limit = std::max(options.pyramid.coarse_max_iterations, o.score_iterations);
  for (int rounds = o.score_iterations; rounds + o.score_iterations <= round_limit;
       rounds += o.score_iterations) {
    const int keep = std::max(o.refine_candidates, (static_cast<int>(scored.size()) + 1) / 2);
    if (keep >= static_cast<int>(scored.size()) && rounds > o.score_iterations) break;
    if (keep < static_cast<int>(scored.size())) scored.resize(keep);
    continue_scored(finest, levels - finest);
  }
  // Successive halving down the pyramid: at each finer level (but the finest) a quarter of
  // the survivors, at least refine_candidates, continue from where they converged; the
  // finer level tells orientations apart that the coarse silhouette does not. A survivor
  // that falls below min_score there gives its place to the next best, up to twice as many
  // tried: a look-alike (a textured occluder, a background pattern) can outscore the object
  // at the coarse level and only the finer one tells them apart.
  for (int level = finest - 1; level >= 1; --level) {
    const int keep = std::max(o.refine_candidates, (static_cast<int>(scored.size()) + 3) / 4);
    std::vector<Scored> survivors;
    int found = 0;
    for (int k = 0; k < static_cast<int>(scored.size()) && k < 2 * keep && found < keep; ++k) {
      Scored c = scored[k];
      if (c.score < o.min_score) break;
      if (!continue_one(&c, level, 1)) continue;
      if (c.score >= o.min_score) ++found;
      survivors.push_back(c);
    }
    scored = std::move(survivors);
    std::sort(scored.begin(), scored.end(), by_score);
  }
  UNSEEN_LOG_DEBUG("scored {} candidates in {:.1f} ms", candidates.size(),
                   timer.ElapsedMilliseconds() - correlation_ms);
  // The best refine_candidates are refined; one whose refinement collapses (below
  // min_score: the coarse levels took a look-alike for the object) gives its place to the
  // next, once.
  int refinements = o.refine_candidates;
  for (int k = 0; k < static_cast<int>(scored.size()) && k < refinements; ++k) {
    if (best.confidence >= options.failure.recover_confidence) break;
    if (scored[k].score < o.min_score) break;
    TrackResult r = tracker_.Align(frame, scored[k].pose, std::min(o.refine_levels, levels));
    times += r.summary.times;
    UNSEEN_LOG_DEBUG("refined candidate {}: conf {:.2f} at {}", scored[k].order, r.confidence,
                     r.world_from_obj.ToString());
    if (r.confidence < o.min_score && refinements == o.refine_candidates) ++refinements;
    if (r.confidence > best.confidence) {
      best = std::move(r);
      choice = scored[k].order;
    }
  }
  best.summary.times = times;
  best.summary.search_candidates = static_cast<int>(candidates.size());
  best.summary.search_choice = choice;
  return best;
}

TrackResult Reacquisition::Seed(const Frame& frame, const Rigid3d& predicted, TrackResult first,
                                bool* from_seed) {
  const std::vector<cv::Mat>& images = frame.images;
  const TrackerOptions& options = tracker_.options();
  const ReacquisitionOptions& o = options.reacquisition;
  *from_seed = false;
  if (!o.use_correlation) return first;
  StageTimes times = first.summary.times;
  Timer timer;
  ReacquisitionOptions seeding = CorrelationOptions();
  seeding.search_radii = o.seed_search_radii;  // the object is near where its motion put it
  const std::vector<CorrelationSeed> seeds =
      FindCorrelationSeeds(images, tracker_.rig(), tracker_.model(), sphere_centre_,
                           sphere_radius_, predicted, seeding, options.preprocess);
  times.preprocess_ms += timer.ElapsedMilliseconds();
  TrackResult best = std::move(first);
  if (!seeds.empty() && seeds[0].max_shift_px >= o.min_seed_shift_px) {
    TrackResult r = tracker_.Align(frame, seeds[0].world_from_obj);
    times += r.summary.times;
    UNSEEN_LOG_DEBUG("correlation seed: shift {:.1f} px at level {}, ncc {:.2f}: conf {:.2f} "
                     "(first {:.2f})",
                     seeds[0].max_shift_px, seeds[0].level, seeds[0].score, r.confidence,
                     best.confidence);
    // A jump needs the evidence of a re-acquisition: a marginal pose far away is more
    // likely a look-alike than the object.
    if (r.confidence >= options.failure.recover_confidence && r.confidence > best.confidence) {
      best = std::move(r);
      *from_seed = true;
    }
    best.summary.search_candidates = 2;
  }
  best.summary.times = times;
  return best;
}

}  // namespace unseen
