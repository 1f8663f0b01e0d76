// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/plane_sweep.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "unseen/util/error.h"
#include "unseen/util/logging.h"

namespace unseen {
namespace {

cv::Mat Box(const cv::Mat& m, int window) {
  cv::Mat out;
  cv::boxFilter(m, out, CV_32F, cv::Size(window, window), cv::Point(-1, -1), true,
                cv::BORDER_REPLICATE);
  return out;
}

cv::Matx33d ToCv(const Eigen::Matrix3d& m) {
  cv::Matx33d out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out(r, c) = m(r, c);
  }
  return out;
}

// The planes for depths [near, far] over region `r` of the reference camera: how far the
// match of the region's centre moves across the range in the other cameras, in steps of
// o.disparity_step_px, capped at o.planes.
int PlaneCount(const Rig& rig, int reference, const std::vector<int>& others, const PixelRect& r,
               double near, double far, const PlaneSweepOptions& o) {
  if (!(o.disparity_step_px > 0.0)) return o.planes;
  const RigCamera& ref = rig.cameras[reference];
  const Eigen::Vector2d centre(0.5 * (r.x0 + r.x1 - 1), 0.5 * (r.y0 + r.y1 - 1));
  double span_px = 0.0;
  for (const int c : others) {
    const RigCamera& cam = rig.cameras[c];
    const Rigid3d other_from_ref = cam.cam_from_world() * ref.world_from_cam;
    const Eigen::Vector3d a = other_from_ref * ref.intrinsics.Unproject(centre, near);
    const Eigen::Vector3d b = other_from_ref * ref.intrinsics.Unproject(centre, far);
    if (!(a.z() > 0.0 && b.z() > 0.0)) return o.planes;  // behind: no bound from this one
    span_px = std::max(span_px, (cam.intrinsics.Project(a) - cam.intrinsics.Project(b)).norm());
  }
  const double needed = std::ceil(span_px / o.disparity_step_px) + 1.0;
  return static_cast<int>(std::clamp(needed, 4.0, static_cast<double>(o.planes)));
}

}  // namespace

PlaneSweepDepth::PlaneSweepDepth(const Rig& rig, int reference,
                                 const DepthExtractionOptions& options)
    : rig_(rig), reference_(reference), options_(options) {
  options_.Check();
  UNSEEN_CHECK(rig_.size() >= 2,
               "depth source planesweep needs two cameras or more; the rig has {}", rig_.size());
}

DepthMap PlaneSweepDepth::Extract(const Frame& frame, const PixelRect& roi, double near_m,
                                  double far_m) const {
  const PlaneSweepOptions& o = options_.plane_sweep;
  const RigCamera& ref = rig_.cameras[reference_];
  const PinholeCamera& kref = ref.intrinsics;
  const cv::Mat ref_grey = GreyImage(frame, rig_, reference_, "planesweep");
  DepthMap out;
  out.texturedness = Texturedness(frame.images[reference_]);
  out.depth = cv::Mat::zeros(kref.height, kref.width, CV_32FC1);
  const PixelRect r = (roi.empty() ? kref.ImageRect() : roi).Intersect(kref.ImageRect());
  const double near = near_m > 0.0 ? near_m : options_.min_depth_m;
  const double far = far_m > 0.0 ? far_m : options_.max_depth_m;
  UNSEEN_CHECK(near > 0.0 && far > near, "depth source planesweep: depth range [{}, {}] m is empty",
               near, far);
  if (r.width() < o.window_px || r.height() < o.window_px) return out;

  // The other cameras with an image this frame.
  std::vector<int> others;
  std::vector<cv::Mat> greys;
  for (int c = 0; c < rig_.size(); ++c) {
    if (c == reference_ || c >= static_cast<int>(frame.images.size()) || frame.images[c].empty()) {
      continue;
    }
    others.push_back(c);
    greys.push_back(GreyImage(frame, rig_, c, "planesweep"));
  }
  UNSEEN_CHECK(!others.empty(),
               "depth source planesweep: frame {} has no image besides camera '{}'", frame.frame_id,
               ref.name);
  const int num_others = static_cast<int>(others.size());
  const int num_best = std::clamp(static_cast<int>(std::lround(o.best_share * num_others)),
                                  std::min(2, num_others), num_others);

  // Work on the region grown by half a window, so that its border pixels have whole windows.
  const int half = o.window_px / 2;
  const PixelRect w = r.Grow(half).Intersect(kref.ImageRect());
  const cv::Rect wrect(w.x0, w.y0, w.width(), w.height());
  const cv::Mat ref_w = ref_grey(wrect);
  const cv::Mat mean_r = Box(ref_w, o.window_px);
  const cv::Mat var_r = Box(ref_w.mul(ref_w), o.window_px) - mean_r.mul(mean_r);

  // Plane k at inverse depth 1/far + k * step (k = 0: the farthest).
  const int planes = PlaneCount(rig_, reference_, others, r, near, far, o);
  UNSEEN_LOG_DEBUG("plane sweep: {} planes over [{:.3f}, {:.3f}] m, {} cameras", planes, near, far,
                   num_others + 1);
  const double inv_far = 1.0 / far;
  const double inv_step = (1.0 / near - inv_far) / (planes - 1);
  const Eigen::Matrix3d kref_inv = kref.K().inverse();
  const cv::Matx33d shift(1, 0, w.x0, 0, 1, w.y0, 0, 0, 1);  // region pixel -> image pixel

  // The cost volume over the region (rows of the grown region, cropped below): filled a
  // plane at a time (row k of by_plane), then transposed so that each pixel's costs are
  // contiguous for the per-pixel passes below (volume[i * planes + k]).
  const int n = w.width() * w.height();
  const int width = w.width();
  cv::Mat by_plane(planes, n, CV_32FC1);
  std::vector<cv::Mat> camera_costs(others.size());
  const bool all_cameras = num_best == num_others;
  std::vector<float> sum(all_cameras ? n : 0);
  cv::Mat warped, stacked(wrect.size(), CV_32FC4), boxed;
  for (int k = 0; k < planes; ++k) {
    const double z = 1.0 / (inv_far + k * inv_step);
    if (all_cameras) std::fill(sum.begin(), sum.end(), 0.0f);
    for (size_t j = 0; j < others.size(); ++j) {
      const RigCamera& cam = rig_.cameras[others[j]];
      const Rigid3d other_from_ref = cam.cam_from_world() * ref.world_from_cam;
      // The plane z = const of the reference camera: X_j = (R + t n^T / z) X_ref.
      Eigen::Matrix3d h = other_from_ref.RotationMatrix();
      h.col(2) += other_from_ref.translation() / z;
      const cv::Matx33d homography = ToCv(cam.intrinsics.K() * h * kref_inv) * shift;
      cv::warpPerspective(greys[j], warped, homography, wrect.size(),
                          cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT, -1.0);
      // One box filter over (warped, warped^2, reference x warped, seen): the window
      // means that make the ZNCC, and the share of the window the other camera sees
      // (warped from outside its image: -1).
      for (int y = 0; y < w.height(); ++y) {
        const float* wp = warped.ptr<float>(y);
        const float* rp = ref_w.ptr<float>(y);
        cv::Vec4f* st = stacked.ptr<cv::Vec4f>(y);
        for (int x = 0; x < width; ++x) {
          const bool seen = wp[x] > -0.5f;
          const float v = seen ? wp[x] : 0.0f;
          st[x] = cv::Vec4f(v, v * v, rp[x] * v, seen ? 1.0f : 0.0f);
        }
      }
      cv::boxFilter(stacked, boxed, CV_32F, cv::Size(o.window_px, o.window_px), cv::Point(-1, -1),
                    true, cv::BORDER_REPLICATE);
      cv::Mat& cost = camera_costs[j];
      if (!all_cameras) cost.create(wrect.size(), CV_32FC1);
      for (int y = 0; y < w.height(); ++y) {
        const float* mr = mean_r.ptr<float>(y);
        const float* vr = var_r.ptr<float>(y);
        const cv::Vec4f* bx = boxed.ptr<cv::Vec4f>(y);
        float* co = all_cameras ? &sum[static_cast<size_t>(y) * width] : cost.ptr<float>(y);
        for (int x = 0; x < width; ++x) {
          const float mean_w = bx[x][0];
          const float var_w = bx[x][1] - mean_w * mean_w;
          const float cross = bx[x][2] - mr[x] * mean_w;
          const float denom = std::sqrt(std::max(vr[x] * var_w, 1e-12f));
          const float ncc = std::clamp(cross / denom, -1.0f, 1.0f);
          const float c = bx[x][3] > 0.999f ? 1.0f - ncc : 2.0f;
          if (all_cameras) {
            co[x] += c;
          } else {
            co[x] = c;
          }
        }
      }
    }
    // The mean of the best cameras' costs.
    if (all_cameras) {
      const float scale = 1.0f / num_best;
      float* row = by_plane.ptr<float>(k);
      for (int i = 0; i < n; ++i) row[i] = sum[i] * scale;
      continue;
    }
    std::vector<float> per_camera(others.size());
    for (int y = 0; y < w.height(); ++y) {
      for (int x = 0; x < width; ++x) {
        for (size_t j = 0; j < others.size(); ++j) per_camera[j] = camera_costs[j].at<float>(y, x);
        // nth_element leaves the num_best smallest in front (unordered).
        std::nth_element(per_camera.begin(), per_camera.begin() + (num_best - 1), per_camera.end());
        float best_sum = 0.0f;
        for (int b = 0; b < num_best; ++b) best_sum += per_camera[b];
        by_plane.at<float>(k, y * width + x) = best_sum / num_best;
      }
    }
  }

  cv::Mat by_pixel;
  cv::transpose(by_plane, by_pixel);
  const float* volume = by_pixel.ptr<float>();

  // Winner takes all, then the smoothness passes: the plane minimising its cost plus
  // smoothness times its distance (in planes) from the median of the 3x3 neighbours'.
  cv::Mat label(wrect.size(), CV_32FC1);
  for (int i = 0; i < n; ++i) {
    const float* costs = &volume[static_cast<size_t>(i) * planes];
    label.at<float>(i / width, i % width) =
        static_cast<float>(std::min_element(costs, costs + planes) - costs);
  }
  const float lambda = static_cast<float>(o.smoothness);
  for (int pass = 0; pass < o.refine_iterations && lambda > 0.0f; ++pass) {
    cv::Mat median;
    cv::medianBlur(label, median, 3);
    for (int i = 0; i < n; ++i) {
      const float m = median.at<float>(i / width, i % width);
      const float* costs = &volume[static_cast<size_t>(i) * planes];
      int best = 0;
      float best_cost = std::numeric_limits<float>::infinity();
      for (int k = 0; k < planes; ++k) {
        const float c = costs[k] + lambda * std::abs(k - m);
        if (c < best_cost) {
          best_cost = c;
          best = k;
        }
      }
      label.at<float>(i / width, i % width) = static_cast<float>(best);
    }
  }

  // Depth where the winner is distinct, good and inside the range, to a fraction of a plane.
  ForEachTexturedPixel(&out, r, options_.min_texturedness, [&](int x, int y, float* depth) {
    const int i = (y - w.y0) * width + (x - w.x0);
    const float* costs = &volume[static_cast<size_t>(i) * planes];
    const int k = static_cast<int>(label.at<float>(y - w.y0, x - w.x0));
    if (k <= 0 || k >= planes - 1) return;  // at the range's ends: likely beyond it
    const float c = costs[k];
    if (c > o.max_cost) return;
    float second = std::numeric_limits<float>::infinity();
    for (int q = 0; q < planes; ++q) {
      if (std::abs(q - k) > 1) second = std::min(second, costs[q]);
    }
    if (second - c < o.uniqueness) return;
    const float cm = costs[k - 1];
    const float cp = costs[k + 1];
    const float curvature = cm - 2.0f * c + cp;
    const float offset =
        curvature > 1e-6f ? std::clamp(0.5f * (cm - cp) / curvature, -0.5f, 0.5f) : 0.0f;
    *depth = static_cast<float>(1.0 / (inv_far + (k + offset) * inv_step));
  });
  // Isolated depths out.
  if (o.min_support > 0) {
    const cv::Mat measured = out.depth.clone();
    for (int y = r.y0; y < r.y1; ++y) {
      for (int x = r.x0; x < r.x1; ++x) {
        const float z = measured.at<float>(y, x);
        if (!(z > 0.0f)) continue;
        int support = 0;
        for (int dy = -2; dy <= 2; ++dy) {
          for (int dx = -2; dx <= 2; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if ((dx == 0 && dy == 0) || xx < 0 || yy < 0 || xx >= measured.cols ||
                yy >= measured.rows) {
              continue;
            }
            support += std::abs(measured.at<float>(yy, xx) - z) < 0.02f * z ? 1 : 0;
          }
        }
        if (support < o.min_support) out.depth.at<float>(y, x) = 0.0f;
      }
    }
  }
  return out;
}

}  // namespace unseen
