// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/object_segmentation.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <numeric>
#include <optional>
#include <random>
#include <vector>

#include "unseen/util/error.h"

namespace unseen {
namespace {

// A measured point with the surface normal the depth map shows there (zero if unknown).
struct Surfel {
  Eigen::Vector3d p;
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
};

struct Plane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset = 0.0;  // normal . p + offset = 0
};

// Whether a point lies on a plane: near it and facing its way (a surface that only crosses
// the plane, as the table beside a box's face crosses the face's plane, is not on it).
// SegmentationOptions::plane_tolerance_m and the cosine of plane_normal_deg are taken once:
// the test runs for every point of every RANSAC hypothesis.
struct PlaneTest {
  double tolerance_m;
  double min_normal_dot;
  explicit PlaneTest(const SegmentationOptions& o)
      : tolerance_m(o.plane_tolerance_m),
        min_normal_dot(std::cos(o.plane_normal_deg * M_PI / 180.0)) {}
  bool Holds(const Plane& plane, const Surfel& s) const {
    return std::abs(plane.normal.dot(s.p) + plane.offset) < tolerance_m &&
           std::abs(plane.normal.dot(s.n)) >= min_normal_dot;
  }
};

// The plane through the most of `points` (RANSAC, seeded) whose inliers hold min_share of
// them, or std::nullopt.
std::optional<Plane> DominantPlane(const std::vector<Surfel>& points,
                                   const std::vector<bool>& excluded, const SegmentationOptions& o,
                                   std::mt19937* rng) {
  std::vector<int> candidates;
  for (int i = 0; i < static_cast<int>(points.size()); ++i) {
    if (!excluded[i]) candidates.push_back(i);
  }
  if (candidates.size() < 3) return std::nullopt;
  std::uniform_int_distribution<size_t> pick(0, candidates.size() - 1);
  // Scored on an even subsample of at most 2 000 points.
  const size_t stride = std::max<size_t>(1, candidates.size() / 2000);
  const PlaneTest on_plane(o);
  Plane best;
  int best_inliers = 0;
  for (int it = 0; it < o.plane_iterations; ++it) {
    const Eigen::Vector3d& a = points[candidates[pick(*rng)]].p;
    const Eigen::Vector3d& b = points[candidates[pick(*rng)]].p;
    const Eigen::Vector3d& c = points[candidates[pick(*rng)]].p;
    const Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() < 1e-9) continue;
    Plane p;
    p.normal = n.normalized();
    p.offset = -p.normal.dot(a);
    int inliers = 0;
    for (size_t i = 0; i < candidates.size(); i += stride) {
      inliers += on_plane.Holds(p, points[candidates[i]]) ? 1 : 0;
    }
    if (inliers > best_inliers) {
      best_inliers = inliers;
      best = p;
    }
  }
  const size_t scored = (candidates.size() + stride - 1) / stride;
  if (best_inliers < o.min_plane_share * scored) return std::nullopt;
  return best;
}

// The support the object stands on: of the dominant planes among `points` (pixels
// `pixels`, all inside the image rectangle `rect`), the first with inliers farther than
// `rim` from `origin` in a connected stretch of the image — a table runs on beyond the
// object, a face of an object smaller than `rim` does not (its plane meets far surfaces in
// scattered lines at most) — and with the points off it mostly on the camera's side: an
// object stands on its support or before it, while the rest of an object lies behind its
// own faces (a large flat side facing the camera, as a van's, reaches past the rim too).
// Up to four planes are tried (a box shows three faces), each one's inliers set aside.
std::optional<Plane> SupportPlane(const std::vector<Surfel>& points,
                                  const std::vector<cv::Point>& pixels, const cv::Rect& rect,
                                  const Eigen::Vector3d& origin, double rim,
                                  const SegmentationOptions& o) {
  std::mt19937 rng(12345);
  const PlaneTest on_plane(o);
  std::vector<bool> excluded(points.size(), false);
  for (int attempt = 0; attempt < 4; ++attempt) {
    const std::optional<Plane> plane = DominantPlane(points, excluded, o, &rng);
    if (!plane) return std::nullopt;
    // Over `rect` only: no inlier lies beyond it, so no stretch leaves it.
    cv::Mat inliers = cv::Mat::zeros(rect.size(), CV_8UC1);
    for (size_t i = 0; i < points.size(); ++i) {
      if (!excluded[i] && on_plane.Holds(*plane, points[i])) {
        inliers.at<uint8_t>(pixels[i] - rect.tl()) = 255;
      }
    }
    cv::Mat labels;
    cv::connectedComponents(inliers, labels, 8, CV_32S);
    // A stretch that reaches beyond the rim ...
    bool reaches = false;
    for (size_t i = 0; i < points.size() && !reaches; ++i) {
      if (excluded[i] || labels.at<int>(pixels[i] - rect.tl()) <= 0) continue;
      reaches = (points[i].p - origin).norm() > rim;
    }
    // ... with what is off the plane before it rather than behind it (the camera, at the
    // frame's origin, is on the side of the sign of the offset).
    int before = 0, behind = 0;
    if (reaches) {
      for (size_t i = 0; i < points.size(); ++i) {
        if (excluded[i]) continue;
        const double distance = plane->normal.dot(points[i].p) + plane->offset;
        if (std::abs(distance) < on_plane.tolerance_m) continue;
        ++((distance > 0.0) == (plane->offset > 0.0) ? before : behind);
      }
    }
    if (reaches && before >= behind) return plane;
    for (size_t i = 0; i < points.size(); ++i) {
      if (on_plane.Holds(*plane, points[i])) excluded[i] = true;
    }
  }
  return std::nullopt;
}

// Connected components of the measured pixels of `pixels` (region `r`'s measured pixels
// that `out` keeps, row by row, x ascending): two are connected when they lie within `gap`
// pixels of each other in x and y and their depths differ by less than `max_step` times
// the depth. Labels from 1 over the region (0: none); per label its pixel count and the
// distance of its nearest point from `origin` (m); index 0 unused.
struct DepthComponents {
  cv::Mat labels;  // CV_32SC1 of the region's size
  std::vector<int> count{0};
  std::vector<double> nearest_m{std::numeric_limits<double>::infinity()};
};

DepthComponents LabelDepthComponents(const DepthMap& depth_map, const PinholeCamera& camera,
                                     const PixelRect& r, const cv::Mat& out,
                                     const std::vector<cv::Point>& pixels,
                                     const Eigen::Vector3d& origin, int gap, double max_step) {
  DepthComponents parts;
  parts.labels = cv::Mat(r.height(), r.width(), CV_32SC1, cv::Scalar(0));
  cv::Mat& labels = parts.labels;
  // A window visits the measured pixels of its rows (row_begin[y - r.y0] is the first of
  // row y) instead of every pixel: image-based depth is sparse.
  std::vector<int> row_begin(r.height() + 1, 0);
  for (const cv::Point& px : pixels) ++row_begin[px.y - r.y0 + 1];
  for (int k = 0; k < r.height(); ++k) row_begin[k + 1] += row_begin[k];
  auto x_less = [](const cv::Point& a, int x) { return a.x < x; };
  const cv::Point tl(r.x0, r.y0);
  std::vector<cv::Point> stack;
  for (const cv::Point& start : pixels) {
    if (!out.at<uint8_t>(start) || labels.at<int>(start - tl) != 0) continue;
    const int label = static_cast<int>(parts.count.size());
    stack.assign(1, start);
    labels.at<int>(start - tl) = label;
    int count = 0;
    double nearest = std::numeric_limits<double>::infinity();
    while (!stack.empty()) {
      const cv::Point p = stack.back();
      stack.pop_back();
      ++count;
      const float z = depth_map.depth.at<float>(p);
      nearest = std::min(nearest, (camera.Unproject(Eigen::Vector2d(p.x, p.y), z) - origin).norm());
      const float step = static_cast<float>(max_step) * z;
      const int x_begin = p.x - gap, x_end = p.x + gap;
      for (int y = std::max(p.y - gap, r.y0); y <= std::min(p.y + gap, r.y1 - 1); ++y) {
        const float* depth_row = depth_map.depth.ptr<float>(y);
        const uint8_t* out_row = out.ptr<uint8_t>(y);
        int* label_row = labels.ptr<int>(y - r.y0) - r.x0;  // indexed by image x
        const auto row_end = pixels.begin() + row_begin[y - r.y0 + 1];
        for (auto q =
                 std::lower_bound(pixels.begin() + row_begin[y - r.y0], row_end, x_begin, x_less);
             q != row_end && q->x <= x_end; ++q) {
          const int x = q->x;
          if (std::abs(depth_row[x] - z) > step || label_row[x] != 0 || !out_row[x]) continue;
          label_row[x] = label;
          stack.emplace_back(x, y);
        }
      }
    }
    parts.count.push_back(count);
    parts.nearest_m.push_back(nearest);
  }
  return parts;
}

}  // namespace

cv::Mat SegmentObject(const DepthMap& depth_map, const PinholeCamera& camera,
                      const PixelRect& region, const Eigen::Vector3d& origin_in_cam,
                      const cv::Mat& given_mask, const SegmentationOptions& options,
                      SegmentationReport* report, MaskRole mask_role) {
  options.Check();
  const cv::Size size(camera.width, camera.height);
  UNSEEN_CHECK(depth_map.depth.type() == CV_32FC1 && depth_map.depth.size() == size,
               "SegmentObject: depth map is {}x{} type {}; expected {}x{} CV_32FC1",
               depth_map.depth.cols, depth_map.depth.rows, depth_map.depth.type(), size.width,
               size.height);
  UNSEEN_CHECK(given_mask.empty() || (given_mask.type() == CV_8UC1 && given_mask.size() == size),
               "SegmentObject: mask is {}x{} type {}; expected {}x{} CV_8UC1", given_mask.cols,
               given_mask.rows, given_mask.type(), size.width, size.height);
  SegmentationReport local;
  SegmentationReport& rep = report ? *report : local;
  rep = SegmentationReport();
  cv::Mat out = cv::Mat::zeros(size, CV_8UC1);
  const PixelRect r = region.Intersect(camera.ImageRect());
  if (r.empty()) return out;
  const cv::Rect rect(r.x0, r.y0, r.width(), r.height());
  out(rect).setTo(255);
  // From here on `out` is empty beyond `rect`: the whole-image steps below look at `rect`.
  cv::Mat out_region = out(rect);
  const cv::Mat depth_region = depth_map.depth(rect);
  const bool mask_selects = !given_mask.empty() && mask_role == MaskRole::kSelects;
  if (!given_mask.empty() && !mask_selects) out_region.setTo(0, given_mask(rect) == 0);
  rep.region_pixels = cv::countNonZero(out_region);

  // The measured points in the region and their distance from the origin.
  std::vector<Eigen::Vector3d> points;
  std::vector<cv::Point> pixels;
  for (int y = r.y0; y < r.y1; ++y) {
    for (int x = r.x0; x < r.x1; ++x) {
      if (!out.at<uint8_t>(y, x)) continue;
      const float z = depth_map.depth.at<float>(y, x);
      if (!(z > 0.0f)) continue;
      points.push_back(camera.Unproject(Eigen::Vector2d(x, y), z));
      pixels.emplace_back(x, y);
    }
  }
  rep.with_depth = static_cast<int>(points.size());
  // Normals from the depth map: the cross product of the horizontal and vertical chords
  // through the pixel (3 px each way).
  std::vector<Surfel> surfels(points.size());
  constexpr int kChord = 3;
  auto point_at = [&](int x, int y, Eigen::Vector3d* p) {
    if (x < 0 || y < 0 || x >= size.width || y >= size.height) return false;
    const float z = depth_map.depth.at<float>(y, x);
    if (!(z > 0.0f)) return false;
    *p = camera.Unproject(Eigen::Vector2d(x, y), z);
    return true;
  };
  for (size_t i = 0; i < points.size(); ++i) {
    surfels[i].p = points[i];
    Eigen::Vector3d l, r, u, d;
    const cv::Point& px = pixels[i];
    if (point_at(px.x - kChord, px.y, &l) && point_at(px.x + kChord, px.y, &r) &&
        point_at(px.x, px.y - kChord, &u) && point_at(px.x, px.y + kChord, &d)) {
      const Eigen::Vector3d n = (r - l).cross(d - u);
      if (n.norm() > 1e-12) surfels[i].n = n.normalized();
    }
  }
  rep.dense = depth_map.dense ||
              (rep.region_pixels > 0 && rep.with_depth >= options.dense_share * rep.region_pixels);
  std::optional<Plane> support;
  if (options.remove_support_plane) {
    std::vector<Surfel> near;
    std::vector<cv::Point> near_pixels;
    for (size_t i = 0; i < points.size(); ++i) {
      if ((points[i] - origin_in_cam).norm() > options.max_radius_m) continue;
      near.push_back(surfels[i]);
      near_pixels.push_back(pixels[i]);
    }
    support =
        SupportPlane(near, near_pixels, rect, origin_in_cam, 0.7 * options.max_radius_m, options);
    rep.plane_found = support.has_value();
    if (support) {
      const double side = support->normal.dot(origin_in_cam) + support->offset >= 0.0 ? 1.0 : -1.0;
      rep.support_plane << side * support->normal, side * support->offset;
    }
  }
  const PlaneTest on_plane(options);
  for (size_t i = 0; i < points.size(); ++i) {
    const cv::Point& px = pixels[i];
    if ((points[i] - origin_in_cam).norm() > options.max_radius_m) {
      ++rep.beyond_radius;
      out.at<uint8_t>(px) = 0;
    } else if (support && on_plane.Holds(*support, surfels[i])) {
      ++rep.on_plane;
      out.at<uint8_t>(px) = 0;
    }
  }
  if (cv::countNonZero(out_region) == 0) return out;

  const int before = cv::countNonZero(out_region & (depth_region > 0.0f));
  // The measured pixels connected in depth: neighbours (dense depth: the 8 around a pixel;
  // sparse depth, which image-based sources measure on textured pixels only: any within
  // sparse_gap_px) whose depths differ by less than max_depth_step of the depth.
  auto label = [&](bool dense) {
    return LabelDepthComponents(depth_map, camera, r, out, pixels, origin_in_cam,
                                dense ? 1 : options.sparse_gap_px, options.max_depth_step);
  };
  DepthComponents parts = label(rep.dense);
  if (parts.count.size() == 1) {  // no measured pixel left
    if (rep.dense) out_region.setTo(0, depth_region <= 0.0f);
    return out;
  }
  std::vector<int> masked;
  int total_masked = 0;
  auto count_masked = [&] {
    masked.assign(parts.count.size(), 0);
    total_masked = 0;
    if (!mask_selects) return;
    const cv::Mat mask_region = given_mask(rect);
    for (int y = 0; y < rect.height; ++y) {
      const int* label_row = parts.labels.ptr<int>(y);
      const uint8_t* mask_row = mask_region.ptr<uint8_t>(y);
      for (int x = 0; x < rect.width; ++x) {
        if (label_row[x] > 0 && mask_row[x]) ++masked[label_row[x]];
      }
    }
    total_masked = std::accumulate(masked.begin(), masked.end(), 0);
  };
  count_masked();
  // Whether component k holds enough of a selecting mask's measured pixels to be the object.
  auto selected = [&](size_t k) {
    return masked[k] > 0 && masked[k] >= options.min_component_share * total_masked;
  };
  // Dense depth: with a selecting mask, of the surfaces holding the mask's measured pixels
  // the nearest the origin (the blocks along a moving object's outline hold the
  // background's side too). Else the component nearest the origin, among those that hold
  // at least min_component_share of the measured pixels within the radius: a sensor's
  // noise, holes and lost pixels along depth steps leave fragments (a thin part, a pixel
  // island) that may come nearer the origin, inside the object, than its visible face.
  // Without such a component (also when a selecting mask lies on no surface), the nearest
  // of all.
  const int within = static_cast<int>(points.size()) - rep.beyond_radius;
  const double min_count = options.min_component_share * within;
  auto nearest_surface = [&] {
    int best = 0;
    if (mask_selects) {
      double best_d = std::numeric_limits<double>::infinity();
      for (size_t k = 1; k < masked.size(); ++k) {
        if (selected(k) && parts.nearest_m[k] < best_d) {
          best_d = parts.nearest_m[k];
          best = static_cast<int>(k);
        }
      }
    }
    double near_d = std::numeric_limits<double>::infinity(), any_d = near_d;
    int near_label = 0, any_label = 0;
    for (size_t k = 1; k < parts.count.size(); ++k) {
      const double d = parts.nearest_m[k];
      if (d < any_d) any_d = d, any_label = static_cast<int>(k);
      if (parts.count[k] >= min_count && d < near_d) near_d = d, near_label = static_cast<int>(k);
    }
    if (best == 0) best = near_label > 0 ? near_label : any_label;
    return best;
  };
  int best_label = 0;
  if (rep.dense) {
    // A dense map that measures the object only in scattered pixels (a sensor's far range:
    // noise and the pixels lost along its steps thin it out) falls apart into islands of a
    // few pixels: then its pixels connect across gaps as sparse depth's do.
    int in_surfaces = 0;  // measured pixels in components of at least min_count
    for (size_t k = 1; k < parts.count.size(); ++k) {
      if (parts.count[k] >= min_count) in_surfaces += parts.count[k];
    }
    if (in_surfaces < options.min_connected_share * before) {
      rep.dense = false;
      rep.fragmented = true;
      parts = label(false);
      count_masked();
    } else {
      best_label = nearest_surface();
    }
  }
  if (rep.dense) {
    // Where the depth is dense, the pixels without depth are not the object's either.
    if (best_label == 0) {
      out_region.setTo(0, depth_region <= 0.0f);
      return out;
    }
    out_region &= parts.labels == best_label;
    rep.unconnected = before - parts.count[best_label];
    return out;
  }
  // Sparse depth: of the components (those a selecting mask selects, if it selects any)
  // the largest that comes within half the radius of the origin is the object's, and the
  // pixels within sparse_fill_px of it its area. Wrong matches on the background (a
  // periodic pattern matches at many depths, some near the origin's) form small components
  // of their own. None near the origin: no object pixels.
  auto largest_near = [&](bool only_selected) {
    int label = 0, count = 0;
    for (size_t k = 1; k < parts.count.size(); ++k) {
      if (parts.nearest_m[k] < 0.5 * options.max_radius_m && parts.count[k] > count &&
          (!only_selected || selected(k))) {
        count = parts.count[k];
        label = static_cast<int>(k);
      }
    }
    return label;
  };
  best_label = mask_selects ? largest_near(true) : 0;
  if (best_label == 0) best_label = largest_near(false);
  if (best_label == 0) {
    out_region.setTo(0);
    rep.unconnected = before;
    return out;
  }
  const cv::Mat component = (parts.labels == best_label) & (depth_region > 0.0f);
  rep.unconnected = before - parts.count[best_label];
  // Dilated over the region only (out is empty beyond it).
  cv::Mat area;
  const int fill = options.sparse_fill_px;
  cv::dilate(component, area,
             cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * fill + 1, 2 * fill + 1)));
  out_region &= area;
  // Measured pixels inside the area that are not connected stay out.
  out_region.setTo(0, (depth_region > 0.0f) & ~component);
  return out;
}

}  // namespace unseen
