// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/plane_sweep.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/thread_pool.h"

namespace unseen {
namespace {

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

// The images of one pyramid level and the plane homographies into them: the plane at
// inverse depth q of the reference camera maps reference pixels to camera j's by
// H_j(q) = K_j (R_j + t_j n^T q) K_ref^-1 = fixed[j] + q * per_inverse_depth[j].
struct SweepLevel {
  cv::Mat reference;            // CV_32FC1 grey
  cv::Mat padded;               // the reference grown by half a window (edges replicated)
  std::vector<cv::Mat> others;  // the other cameras' greys
  std::vector<cv::Matx33d> fixed, per_inverse_depth;
};

void PadReference(SweepLevel* level, int half_window) {
  cv::copyMakeBorder(level->reference, level->padded, half_window, half_window, half_window,
                     half_window, cv::BORDER_REPLICATE);
}

// Level 1 of `level0` (half size, cv::pyrDown; reference padded by `half_window`): pixel x
// of level 0 is (x + 0.5) / 2 - 0.5 of level 1, so H_1 = S H_0 S^-1.
SweepLevel HalfLevel(const SweepLevel& level0, int half_window) {
  SweepLevel out;
  cv::pyrDown(level0.reference, out.reference);
  for (const cv::Mat& g : level0.others) {
    out.others.emplace_back();
    cv::pyrDown(g, out.others.back());
  }
  PadReference(&out, half_window);
  const cv::Matx33d s(0.5, 0, -0.25, 0, 0.5, -0.25, 0, 0, 1);
  const cv::Matx33d s_inv(2, 0, 0.5, 0, 2, 0.5, 0, 0, 1);
  for (size_t j = 0; j < level0.fixed.size(); ++j) {
    out.fixed.push_back(s * level0.fixed[j] * s_inv);
    out.per_inverse_depth.push_back(s * level0.per_inverse_depth[j] * s_inv);
  }
  return out;
}

// The sweep's planes: plane k at inverse depth inv_far + k * inv_step (k = 0: the farthest).
struct Planes {
  double inv_far = 0.0, inv_step = 0.0;
  int count = 0;
  double InverseDepth(double k) const { return inv_far + k * inv_step; }
};

// Buffers of one tile's cost computation, reused from tile to tile: planar channels of the
// tile grown by half a window (q: warped value, its square, its product with the reference,
// seen or not) and their window sums over the tile.
struct TileScratch {
  std::vector<float> q[4], row_sums[4], sums[4], mean_r, var_r;
  std::vector<float> costs;  // the tile's costs, for the callers
  std::vector<std::vector<float>> camera_costs;
  std::vector<float> per_camera;
};

// Window sums of the planar channel `in` ((w + window - 1) x (h + window - 1), row-major)
// over window x window: out (w x h) at (x, y) sums in over [x, x + window) x [y, y + window).
// Running sums down the columns, then running sums along the rows.
void WindowSums(const float* in, int w, int h, int window, float* column_sums, float* out) {
  const int gw = w + window - 1;
  float* cs = column_sums;
  for (int x = 0; x < gw; ++x) cs[x] = 0.0f;
  for (int j = 0; j < window; ++j) {
    const float* row = in + j * gw;
    for (int x = 0; x < gw; ++x) cs[x] += row[x];
  }
  for (int y = 0; y < h; ++y) {
    float* c = column_sums + y * gw;
    if (y > 0) {
      const float* prev = c - gw;
      const float* enter = in + (y + window - 1) * gw;
      const float* leave = in + (y - 1) * gw;
      for (int x = 0; x < gw; ++x) c[x] = prev[x] + enter[x] - leave[x];
    }
    float* o = out + y * w;
    float run = 0.0f;
    for (int i = 0; i < window; ++i) run += c[i];
    o[0] = run;
    for (int x = 1; x < w; ++x) {
      run += c[x + window - 1] - c[x - 1];
      o[x] = run;
    }
  }
}

// The ZNCC plane costs (the mean of the best cameras' 1 - ZNCC, 2 where a camera does not
// see the whole window) at the pixels of `tile` (level pixels), for the planes `plane_ids`:
// costs[p * tile.area() + i] for plane_ids[p], i row-major in the tile; with `parts`, plane p
// only over (*parts)[p] (tile pixels; 2 elsewhere). Each camera's image
// is warped (bilinear) by the plane's homography over the tile grown by half a window, and
// the window sums of (warped, warped^2, reference x warped, seen) make the ZNCC.
// Written out rather than cv::warpPerspective + cv::boxFilter: on tiles of 32x32 pixels
// with a band of planes each, OpenCV's cost per call (checks, thread dispatch) outweighed
// the arithmetic (measured 4x slower on the 5-camera cube); here one pass runs through
// buffers that stay in the cache.
void TileCosts(const SweepLevel& level, const Planes& planes, const cv::Rect& tile,
               const std::vector<int>& plane_ids, const std::vector<cv::Rect>* parts, int window,
               int num_best, TileScratch* s, float* costs) {
  const int half = window / 2;
  const int w = tile.width, h = tile.height, area = tile.area();
  const int gw = w + 2 * half, gh = h + 2 * half;
  for (int c = 0; c < 4; ++c) {
    s->q[c].resize(static_cast<size_t>(gw) * gh);
    s->row_sums[c].resize(static_cast<size_t>(gw) * h);
    s->sums[c].resize(area);
  }
  // The reference's window means and variances (the padded reference: grown pixel (0, 0)
  // is padded pixel (tile.x, tile.y)).
  std::vector<float>& ref = s->q[0];
  std::vector<float>& ref_sq = s->q[1];
  for (int y = 0; y < gh; ++y) {
    const float* rp = level.padded.ptr<float>(tile.y + y) + tile.x;
    for (int x = 0; x < gw; ++x) {
      ref[y * gw + x] = rp[x];
      ref_sq[y * gw + x] = rp[x] * rp[x];
    }
  }
  s->mean_r.resize(area);
  s->var_r.resize(area);
  const float inv_n = 1.0f / static_cast<float>(window * window);
  WindowSums(ref.data(), w, h, window, s->row_sums[0].data(), s->mean_r.data());
  WindowSums(ref_sq.data(), w, h, window, s->row_sums[1].data(), s->var_r.data());
  for (int i = 0; i < area; ++i) {
    s->mean_r[i] *= inv_n;
    s->var_r[i] = s->var_r[i] * inv_n - s->mean_r[i] * s->mean_r[i];
  }

  const int num_others = static_cast<int>(level.others.size());
  const bool all_cameras = num_best == num_others;
  s->camera_costs.resize(num_others);
  s->per_camera.resize(num_others);
  for (size_t p = 0; p < plane_ids.size(); ++p) {
    const double inverse_depth = planes.InverseDepth(plane_ids[p]);
    float* out = costs + p * area;
    std::fill(out, out + area, all_cameras ? 0.0f : 2.0f);
    // The part of the tile this plane is wanted in (tile pixels), grown by half a window.
    const cv::Rect part = parts ? (*parts)[p] : cv::Rect(0, 0, w, h);
    const int pw = part.width, ph = part.height;
    const int pgw = pw + 2 * half, pgh = ph + 2 * half;
    const double x_first = tile.x + part.x - half, y_first = tile.y + part.y - half;
    for (int j = 0; j < num_others; ++j) {
      const cv::Mat& image = level.others[j];
      const cv::Matx33d hm = level.fixed[j] + inverse_depth * level.per_inverse_depth[j];
      // Where the grown part's corners all land inside the image, so does all of it (a
      // homography keeps the part a convex quadrilateral): no bounds to check, all seen.
      const float max_x = static_cast<float>(image.cols - 1) - 1e-3f;
      const float max_y = static_cast<float>(image.rows - 1) - 1e-3f;
      auto inside = [&](double px, double py) {
        const double hz = hm(2, 0) * px + hm(2, 1) * py + hm(2, 2);
        const double sx = (hm(0, 0) * px + hm(0, 1) * py + hm(0, 2)) / hz;
        const double sy = (hm(1, 0) * px + hm(1, 1) * py + hm(1, 2)) / hz;
        return hz > 0.0 && sx >= 0.0 && sy >= 0.0 && sx <= max_x && sy <= max_y;
      };
      const bool all_inside = inside(x_first, y_first) && inside(x_first + pgw - 1, y_first) &&
                              inside(x_first, y_first + pgh - 1) &&
                              inside(x_first + pgw - 1, y_first + pgh - 1);
      const cv::Matx33f hf(hm);
      const float* pixels = image.ptr<float>();
      const size_t stride = image.step1();
      for (int y = 0; y < pgh; ++y) {
        const float py = static_cast<float>(y_first + y);
        const float* rp = level.padded.ptr<float>(tile.y + part.y + y) + tile.x + part.x;
        float* q0 = &s->q[0][y * pgw];
        float* q1 = &s->q[1][y * pgw];
        float* q2 = &s->q[2][y * pgw];
        float* q3 = &s->q[3][y * pgw];
        float hx = hf(0, 0) * static_cast<float>(x_first) + hf(0, 1) * py + hf(0, 2);
        float hy = hf(1, 0) * static_cast<float>(x_first) + hf(1, 1) * py + hf(1, 2);
        float hz = hf(2, 0) * static_cast<float>(x_first) + hf(2, 1) * py + hf(2, 2);
        for (int x = 0; x < pgw; ++x, hx += hf(0, 0), hy += hf(1, 0), hz += hf(2, 0)) {
          const float inv_z = 1.0f / hz;
          const float sx = hx * inv_z, sy = hy * inv_z;
          float v = 0.0f, seen = 1.0f;
          if (all_inside || (hz > 0.0f && sx >= 0.0f && sy >= 0.0f && sx <= max_x && sy <= max_y)) {
            const int x0 = static_cast<int>(sx), y0 = static_cast<int>(sy);
            const float fx = sx - static_cast<float>(x0), fy = sy - static_cast<float>(y0);
            const float* r0 = pixels + y0 * stride + x0;
            const float* r1 = r0 + stride;
            v = (1.0f - fy) * ((1.0f - fx) * r0[0] + fx * r0[1]) +
                fy * ((1.0f - fx) * r1[0] + fx * r1[1]);
          } else {
            seen = 0.0f;
          }
          q0[x] = v;
          q1[x] = v * v;
          q2[x] = rp[x] * v;
          q3[x] = seen;
        }
      }
      for (int c = 0; c < (all_inside ? 3 : 4); ++c) {
        WindowSums(s->q[c].data(), pw, ph, window, s->row_sums[c].data(), s->sums[c].data());
      }
      std::vector<float>& cost = s->camera_costs[j];
      if (!all_cameras) cost.resize(area);
      float* co = all_cameras ? out : cost.data();
      const float all_seen = static_cast<float>(window * window) - 0.5f;
      for (int y = 0; y < ph; ++y) {
        for (int x = 0; x < pw; ++x) {
          const int i = y * pw + x;                     // in the part
          const int t = (part.y + y) * w + part.x + x;  // in the tile
          const float mean_w = s->sums[0][i] * inv_n;
          const float var_w = s->sums[1][i] * inv_n - mean_w * mean_w;
          const float cross = s->sums[2][i] * inv_n - s->mean_r[t] * mean_w;
          const float denom = std::sqrt(std::max(s->var_r[t] * var_w, 1e-12f));
          const float ncc = std::clamp(cross / denom, -1.0f, 1.0f);
          const float c = all_inside || s->sums[3][i] > all_seen ? 1.0f - ncc : 2.0f;
          co[t] = all_cameras ? co[t] + c : c;
        }
      }
    }
    for (int y = part.y; y < part.y + ph; ++y) {
      for (int t = y * w + part.x; t < y * w + part.x + pw; ++t) {
        if (all_cameras) {
          out[t] /= static_cast<float>(num_best);
          continue;
        }
        // The mean of the best cameras' costs; nth_element leaves the num_best smallest in
        // front (unordered).
        for (int j = 0; j < num_others; ++j) s->per_camera[j] = s->camera_costs[j][t];
        std::nth_element(s->per_camera.begin(), s->per_camera.begin() + (num_best - 1),
                         s->per_camera.end());
        float best_sum = 0.0f;
        for (int b = 0; b < num_best; ++b) best_sum += s->per_camera[b];
        out[t] = best_sum / num_best;
      }
    }
  }
}

constexpr int kTile = 32;  // side of the tiles the costs are computed in, level pixels

// The tiles of kTile x kTile pixels covering `region`.
std::vector<cv::Rect> Tiles(const cv::Rect& region) {
  std::vector<cv::Rect> tiles;
  for (int y = region.y; y < region.y + region.height; y += kTile) {
    for (int x = region.x; x < region.x + region.width; x += kTile) {
      tiles.push_back(cv::Rect(x, y, kTile, kTile) & region);
    }
  }
  return tiles;
}

// Runs fn(tile, scratch) for every tile, spread over the pool's threads (tile t on task
// t mod size, each task with scratch of its own).
template <typename Scratch, typename Fn>
void ForEachTile(ThreadPool* pool, const std::vector<cv::Rect>& tiles, Fn&& fn) {
  const int tasks = std::min(pool->size(), static_cast<int>(tiles.size()));
  pool->ParallelFor(tasks, [&](int task) {
    Scratch scratch;
    for (size_t t = task; t < tiles.size(); t += tasks) fn(tiles[t], &scratch);
  });
}

// The whole cost volume of `region` (level pixels) over the planes first, first + stride,
// ... (count): volume[i * count + p], i row-major in the region (each pixel's costs
// contiguous for the per-pixel passes).
std::vector<float> CostVolume(const SweepLevel& level, const Planes& planes, const cv::Rect& region,
                              int first, int stride, int count, int window, int num_best,
                              ThreadPool* pool) {
  std::vector<float> volume(static_cast<size_t>(region.area()) * count);
  std::vector<int> plane_ids(count);
  for (int p = 0; p < count; ++p) plane_ids[p] = first + p * stride;
  ForEachTile<TileScratch>(pool, Tiles(region), [&](const cv::Rect& tile, TileScratch* scratch) {
    scratch->costs.resize(static_cast<size_t>(tile.area()) * count);
    TileCosts(level, planes, tile, plane_ids, nullptr, window, num_best, scratch,
              scratch->costs.data());
    for (int y = 0; y < tile.height; ++y) {
      for (int x = 0; x < tile.width; ++x) {
        const size_t i =
            static_cast<size_t>(tile.y - region.y + y) * region.width + (tile.x - region.x + x);
        const size_t t = static_cast<size_t>(y) * tile.width + x;
        for (int p = 0; p < count; ++p) {
          volume[i * count + p] = scratch->costs[p * static_cast<size_t>(tile.area()) + t];
        }
      }
    }
  });
  return volume;
}

// Winner takes all, then the thesis's smoothness passes: per pixel, the plane minimising its
// cost plus `smoothness` times its distance (in planes) from the median of the 3x3
// neighbours' planes. CV_32FC1 plane index per pixel of `size`.
cv::Mat SmoothLabels(const std::vector<float>& volume, int count, const cv::Size& size,
                     const PlaneSweepOptions& o) {
  cv::Mat label(size, CV_32FC1);
  const int n = size.area();
  float* l = label.ptr<float>();
  for (int i = 0; i < n; ++i) {
    const float* costs = &volume[static_cast<size_t>(i) * count];
    l[i] = static_cast<float>(std::min_element(costs, costs + count) - costs);
  }
  const float lambda = static_cast<float>(o.smoothness);
  for (int pass = 0; pass < o.refine_iterations && lambda > 0.0f; ++pass) {
    cv::Mat median;
    cv::medianBlur(label, median, 3);
    const float* m = median.ptr<float>();
    for (int i = 0; i < n; ++i) {
      const float* costs = &volume[static_cast<size_t>(i) * count];
      int best = 0;
      float best_cost = std::numeric_limits<float>::infinity();
      for (int k = 0; k < count; ++k) {
        const float c = costs[k] + lambda * std::abs(k - m[i]);
        if (c < best_cost) {
          best_cost = c;
          best = k;
        }
      }
      l[i] = static_cast<float>(best);
    }
  }
  return label;
}

// The plane, to a fraction (a parabola through the neighbouring costs), of a pixel with
// costs[0, count) for consecutive planes of the sweep that chose index k of [lo, hi]: an
// index into costs, NaN when the choice is at an end of [lo, hi] (of the sweep: likely
// beyond the range; of a band: the minimum may lie outside), too costly, or not distinct
// from every non-adjacent plane of costs.
float SubPlaneAt(const float* costs, int count, int k, int lo, int hi, const PlaneSweepOptions& o) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  if (k <= lo || k >= hi) return nan;
  const float c = costs[k];
  if (c > o.max_cost) return nan;
  float second = std::numeric_limits<float>::infinity();
  for (int q = 0; q < count; ++q) {
    if (std::abs(q - k) > 1) second = std::min(second, costs[q]);
  }
  if (second - c < o.uniqueness) return nan;
  const float cm = costs[k - 1];
  const float cp = costs[k + 1];
  const float curvature = cm - 2.0f * c + cp;
  const float offset =
      curvature > 1e-6f ? std::clamp(0.5f * (cm - cp) / curvature, -0.5f, 0.5f) : 0.0f;
  return static_cast<float>(k) + offset;
}

// Where the plane of each pixel of a level's region was found: a plane of the sweep (to a
// fraction), -1 where none was.
using PlaneMap = cv::Mat;  // CV_32FC1 over the level's region

// The pass of a pyramid level below the first: per pixel, only the planes on that level's
// grid (every `stride`-th) within band_planes grid steps of the planes found at the 3x3
// pixels about it one level up (`above` over `region_above`). Calls found(x, y, plane) for
// each pixel (level pixels) whose plane it finds; with `texturedness` only for the pixels
// textured enough.
template <typename Found>
void BandPass(const SweepLevel& level, const Planes& planes, const cv::Rect& region, int stride,
              const PlaneMap& above, const cv::Rect& region_above, const cv::Mat& texturedness,
              float min_texturedness, int window, int num_best, const PlaneSweepOptions& o,
              ThreadPool* pool, Found&& found) {
  const int grid = (planes.count - 1) / stride + 1;  // planes 0, stride, ... on this level
  const float band = static_cast<float>(o.band_planes * stride);
  struct BandScratch : TileScratch {
    std::vector<int> lo, hi, plane_ids, slot;
    std::vector<cv::Rect> wanted;  // per grid plane, the part of the tile that wants it
    std::vector<cv::Rect> parts;   // per plane of plane_ids
    std::vector<float> pixel_costs;
  };
  ForEachTile<BandScratch>(pool, Tiles(region), [&](const cv::Rect& tile, BandScratch* f) {
    f->lo.resize(tile.area());
    f->hi.resize(tile.area());
    f->wanted.assign(grid, cv::Rect());
    f->slot.resize(grid);
    f->pixel_costs.resize(grid);
    for (int y = 0; y < tile.height; ++y) {
      const float* tex = texturedness.empty() ? nullptr : texturedness.ptr<float>(tile.y + y);
      for (int x = 0; x < tile.width; ++x) {
        const int t = y * tile.width + x;
        float k_min = std::numeric_limits<float>::infinity(), k_max = -k_min;
        if (!tex || tex[tile.x + x] >= min_texturedness) {
          const int cx = (tile.x + x) / 2 - region_above.x;
          const int cy = (tile.y + y) / 2 - region_above.y;
          for (int yy = std::max(cy - 1, 0); yy <= std::min(cy + 1, region_above.height - 1);
               ++yy) {
            const float* l = above.ptr<float>(yy);
            for (int xx = std::max(cx - 1, 0); xx <= std::min(cx + 1, region_above.width - 1);
                 ++xx) {
              if (l[xx] < 0.0f) continue;
              k_min = std::min(k_min, l[xx]);
              k_max = std::max(k_max, l[xx]);
            }
          }
        }
        // Grid indices; an empty band (lo > hi) where nothing was found about the pixel.
        f->lo[t] =
            k_max < 0.0f ? 1 : std::max(static_cast<int>(std::floor((k_min - band) / stride)), 0);
        f->hi[t] = k_max < 0.0f
                       ? 0
                       : std::min(static_cast<int>(std::ceil((k_max + band) / stride)), grid - 1);
        for (int k = f->lo[t]; k <= f->hi[t]; ++k) f->wanted[k] |= cv::Rect(x, y, 1, 1);
      }
    }
    f->plane_ids.clear();
    f->parts.clear();
    for (int k = 0; k < grid; ++k) {
      f->slot[k] = static_cast<int>(f->plane_ids.size());
      if (f->wanted[k].empty()) continue;
      f->plane_ids.push_back(k * stride);
      f->parts.push_back(f->wanted[k]);
    }
    if (f->plane_ids.empty()) return;
    f->costs.resize(static_cast<size_t>(tile.area()) * f->plane_ids.size());
    TileCosts(level, planes, tile, f->plane_ids, &f->parts, window, num_best, f, f->costs.data());
    for (int t = 0; t < tile.area(); ++t) {
      if (f->lo[t] > f->hi[t]) continue;
      const int count = f->hi[t] - f->lo[t] + 1;
      for (int p = 0; p < count; ++p) {
        f->pixel_costs[p] = f->costs[static_cast<size_t>(f->slot[f->lo[t] + p]) * tile.area() + t];
      }
      const float* c = f->pixel_costs.data();
      const int k = static_cast<int>(std::min_element(c, c + count) - c);
      const float index = SubPlaneAt(c, count, k, 0, count - 1, o);
      if (std::isfinite(index)) {
        found(tile.x + t % tile.width, tile.y + t / tile.width, (f->lo[t] + index) * stride);
      }
    }
  });
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
  SweepLevel level0;
  level0.reference = GreyImage(frame, rig_, reference_, "planesweep");
  PadReference(&level0, o.window_px / 2);
  DepthMap out;
  out.depth = cv::Mat::zeros(kref.height, kref.width, CV_32FC1);
  const PixelRect r = (roi.empty() ? kref.ImageRect() : roi).Intersect(kref.ImageRect());
  out.texturedness = Texturedness(frame.images[reference_], r);
  const double near = near_m > 0.0 ? near_m : options_.min_depth_m;
  const double far = far_m > 0.0 ? far_m : options_.max_depth_m;
  UNSEEN_CHECK(near > 0.0 && far > near, "depth source planesweep: depth range [{}, {}] m is empty",
               near, far);
  if (r.width() < o.window_px || r.height() < o.window_px) return out;

  // The other cameras with an image this frame, and their plane homographies.
  std::vector<int> others;
  const Eigen::Matrix3d kref_inv = kref.K().inverse();
  for (int c = 0; c < rig_.size(); ++c) {
    if (c == reference_ || c >= static_cast<int>(frame.images.size()) || frame.images[c].empty()) {
      continue;
    }
    others.push_back(c);
    level0.others.push_back(GreyImage(frame, rig_, c, "planesweep"));
    const RigCamera& cam = rig_.cameras[c];
    const Rigid3d other_from_ref = cam.cam_from_world() * ref.world_from_cam;
    // The plane z = 1 / q of the reference camera: X_j = (R + t n^T q) X_ref.
    Eigen::Matrix3d t_n = Eigen::Matrix3d::Zero();
    t_n.col(2) = other_from_ref.translation();
    level0.fixed.push_back(ToCv(cam.intrinsics.K() * other_from_ref.RotationMatrix() * kref_inv));
    level0.per_inverse_depth.push_back(ToCv(cam.intrinsics.K() * t_n * kref_inv));
  }
  UNSEEN_CHECK(!others.empty(),
               "depth source planesweep: frame {} has no image besides camera '{}'", frame.frame_id,
               ref.name);
  const int num_others = static_cast<int>(others.size());
  const int num_best = std::clamp(static_cast<int>(std::lround(o.best_share * num_others)),
                                  std::min(2, num_others), num_others);

  Planes planes;
  planes.count = PlaneCount(rig_, reference_, others, r, near, far, o);
  planes.inv_far = 1.0 / far;
  planes.inv_step = (1.0 / near - planes.inv_far) / (planes.count - 1);
  const int window = o.window_px;
  // The pyramid (level l: half the size of level l - 1), as deep as o.levels asks while the
  // region still holds a window and the coarsest level keeps at least 8 planes (a choice
  // needs neighbours on both sides).
  int max_levels = o.levels;
  while (max_levels > 1 && (planes.count - 1) / (1 << (max_levels - 1)) + 1 < 8) --max_levels;
  std::vector<SweepLevel> levels;
  std::vector<cv::Rect> regions{ToCvRect(r)};
  levels.push_back(std::move(level0));
  while (static_cast<int>(levels.size()) < max_levels) {
    const cv::Rect& prev = regions.back();
    const cv::Rect next =
        cv::Rect(cv::Point(prev.x / 2, prev.y / 2),
                 cv::Point((prev.x + prev.width + 1) / 2, (prev.y + prev.height + 1) / 2)) &
        cv::Rect(0, 0, (levels.back().reference.cols + 1) / 2,
                 (levels.back().reference.rows + 1) / 2);
    if (next.width < window || next.height < window) break;
    levels.push_back(HalfLevel(levels.back(), window / 2));
    regions.push_back(next);
  }
  const int top = static_cast<int>(levels.size()) - 1;
  UNSEEN_LOG_DEBUG("plane sweep: {} planes over [{:.3f}, {:.3f}] m, {} cameras, {} levels",
                   planes.count, near, far, num_others + 1, top + 1);
  const float min_t = static_cast<float>(options_.min_texturedness);
  // A pool per map rather than one kept by the source: Extract may be called from several
  // threads at once (a pool runs one loop at a time); starting threads costs far less than
  // a map.
  ThreadPool pool(o.threads);
  auto set_depth = [&](int x, int y, float plane) {
    out.depth.at<float>(y, x) = static_cast<float>(1.0 / planes.InverseDepth(plane));
  };

  // The first (coarsest) level: every 2^top-th plane at every pixel, the thesis's
  // smoothness passes, the sub-plane fit.
  const int top_stride = 1 << top;
  const int top_count = (planes.count - 1) / top_stride + 1;
  const cv::Rect& top_region = regions[top];
  const std::vector<float> volume = CostVolume(levels[top], planes, top_region, 0, top_stride,
                                               top_count, window, num_best, &pool);
  const cv::Mat label = SmoothLabels(volume, top_count, top_region.size(), o);
  // Planes behind the range (negative plane indices: inverse depths below inv_far), out to
  // the farthest depth accepted: each pixel's best cost there.
  std::vector<float> behind_best;
  const double inv_farthest = 1.0 / options_.max_depth_m;
  const int behind_count =
      o.search_behind && planes.inv_far > inv_farthest
          ? std::min(64, static_cast<int>((planes.inv_far - inv_farthest) /
                                          (planes.inv_step * top_stride)))
          : 0;
  if (behind_count > 0) {
    const std::vector<float> behind =
        CostVolume(levels[top], planes, top_region, -behind_count * top_stride, top_stride,
                   behind_count, window, num_best, &pool);
    behind_best.resize(top_region.area());
    for (size_t i = 0; i < behind_best.size(); ++i) {
      behind_best[i] = *std::min_element(behind.begin() + i * behind_count,
                                         behind.begin() + (i + 1) * behind_count);
    }
  }
  PlaneMap found(top_region.size(), CV_32FC1, cv::Scalar(-1.0f));
  for (int y = 0; y < top_region.height; ++y) {
    for (int x = 0; x < top_region.width; ++x) {
      const int i = y * top_region.width + x;
      if (top == 0 && out.texturedness.at<float>(y + r.y0, x + r.x0) < min_t) continue;
      if (!behind_best.empty() &&
          behind_best[i] < volume[static_cast<size_t>(i) * top_count +
                                  static_cast<int>(label.at<float>(y, x))] +
                               o.uniqueness) {
        continue;  // the background: matched behind the object's range as well or better
      }
      const float index = SubPlaneAt(&volume[static_cast<size_t>(i) * top_count], top_count,
                                     static_cast<int>(label.at<float>(y, x)), 0, top_count - 1, o);
      if (!std::isfinite(index)) continue;
      if (top == 0) {
        set_depth(x + r.x0, y + r.y0, index);
      } else {
        found.at<float>(y, x) = index * top_stride;
      }
    }
  }
  // Down the pyramid: a band of planes about what the level above found.
  for (int l = top - 1; l >= 0; --l) {
    const cv::Rect& region = regions[l];
    if (l == 0) {
      BandPass(levels[0], planes, region, 1, found, regions[1], out.texturedness, min_t, window,
               num_best, o, &pool, set_depth);
      break;
    }
    PlaneMap here(region.size(), CV_32FC1, cv::Scalar(-1.0f));
    BandPass(levels[l], planes, region, 1 << l, found, regions[l + 1], cv::Mat(), 0.0f, window,
             num_best, o, &pool, [&](int x, int y, float plane) {
               here.at<float>(y - region.y, x - region.x) = plane;
             });
    found = here;
  }

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
