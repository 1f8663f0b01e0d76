// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/correlation_seeds.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "unseen/image/filters.h"
#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"

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

}  // namespace unseen
