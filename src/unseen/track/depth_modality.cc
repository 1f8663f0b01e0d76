// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/depth_modality.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "unseen/util/error.h"

namespace unseen {

void DepthModalityOptions::Check() const {
  UNSEEN_CHECK(max_points >= 6 && max_points <= 1000000, "depth.max_points {} must be in [6, 1e6]",
               max_points);
  UNSEEN_CHECK(max_distance_m > 0.0 && std::isfinite(max_distance_m),
               "depth.max_distance_m {} must be > 0", max_distance_m);
  residual.Check("depth");
  UNSEEN_CHECK(occluder_margin_m >= 0.0 && std::isfinite(occluder_margin_m),
               "depth.occluder_margin_m {} must be >= 0", occluder_margin_m);
  UNSEEN_CHECK(occluder_margin_sigmas >= 0.0 && std::isfinite(occluder_margin_sigmas),
               "depth.occluder_margin_sigmas {} must be >= 0", occluder_margin_sigmas);
  UNSEEN_CHECK(roughness_noise_factor > 0.0 && !std::isnan(roughness_noise_factor),
               "depth.roughness_noise_factor {} must be > 0", roughness_noise_factor);
  UNSEEN_CHECK(occluder_slope_px >= 0.0 && std::isfinite(occluder_slope_px),
               "depth.occluder_slope_px {} must be >= 0", occluder_slope_px);
  UNSEEN_CHECK(agree_distance_m > 0.0 && std::isfinite(agree_distance_m),
               "depth.agree_distance_m {} must be > 0", agree_distance_m);
  UNSEEN_CHECK(0.0 <= bad_agreement && bad_agreement < good_agreement && good_agreement <= 1.0,
               "depth: need 0 <= bad_agreement ({}) < good_agreement ({}) <= 1", bad_agreement,
               good_agreement);
  UNSEEN_CHECK(min_measured >= 1, "depth.min_measured {} must be >= 1", min_measured);
  UNSEEN_CHECK(max_hidden_share > 0.0 && max_hidden_share <= 1.0,
               "depth.max_hidden_share {} must be in (0, 1]", max_hidden_share);
}

DepthCounts& DepthCounts::operator+=(const DepthCounts& o) {
  sampled += o.sampled;
  measured += o.measured;
  agreeing += o.agreeing;
  hidden += o.hidden;
  used += o.used;
  return *this;
}

double DepthCounts::Agreement(const DepthModalityOptions& options) const {
  if (measured < options.min_measured) return -1.0;
  // Nearly all of it behind other surfaces: either the object is hidden, or the pose is
  // far behind it; neither is a pose to trust.
  if (double(hidden) > options.max_hidden_share * double(measured)) return 0.0;
  return double(agreeing) / double(measured - hidden);
}

namespace {

// A sampled rendered pixel and the measured point it is paired with.
struct DepthPair {
  int x, y;     // rendered pixel (roi)
  int mx, my;   // measured pixel (full resolution)
  float z, zm;  // rendered and measured depth, metres
  double dz;    // zm - z
  float slope;  // rendered depth change per full-resolution pixel, metres
};

// How much nearer than the rendered surface a measured one must be to be an occluder,
// metres (before the slope term); 0: off. At least occluder_margin_m, and
// occluder_margin_sigmas times the sensor's noise, taken as the pairs' robust spread within
// the gate, capped at roughness_noise_factor times the measured surface's roughness between
// neighbouring pixels: the spread counts the pose's error and any occluder too (a hand
// covering half of a box's face spread it to 6 mm, and the margin grew past the hand),
// the roughness sees the sensor's noise alone (on object and occluder alike), but only the
// part of it that is independent from pixel to pixel.
double OccluderMargin(const std::vector<DepthPair>& pairs, double gate, const cv::Mat& measured,
                      const DepthModalityOptions& options) {
  if (options.occluder_margin_m <= 0.0) return 0.0;
  thread_local std::vector<float> values;
  values.clear();
  for (const DepthPair& pair : pairs) {
    if (std::abs(pair.dz) <= gate) values.push_back(float(pair.dz));
  }
  if (values.size() < 10) return options.occluder_margin_m;
  auto middle = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), middle, values.end());
  const float median = *middle;
  for (float& v : values) v = std::abs(v - median);
  double sigma = RobustSigma(&values);
  // Second differences of three neighbouring pixels: sqrt(6) times the noise.
  values.clear();
  for (const DepthPair& pair : pairs) {
    if (pair.mx < 1 || pair.mx + 1 >= measured.cols) continue;
    const float* row = measured.ptr<float>(pair.my);
    const float left = row[pair.mx - 1], right = row[pair.mx + 1];
    if (!(left > 0.0f) || !(right > 0.0f)) continue;
    values.push_back(std::abs(left - 2.0f * pair.zm + right));
  }
  if (values.size() >= 10) {
    sigma = std::min(sigma, options.roughness_noise_factor * RobustSigma(&values) / std::sqrt(6.0));
  }
  return std::max(options.occluder_margin_m, options.occluder_margin_sigmas * sigma);
}

}  // namespace

void AddDepthEquations(const DepthModalityInput& in, const DepthModalityOptions& options,
                       FlowEquations* out, DepthCounts* counts) {
  const cv::Mat& rendered = *in.rendered_depth;
  const cv::Mat& measured = *in.measured_depth;
  UNSEEN_CHECK(rendered.type() == CV_32FC1 && measured.type() == CV_32FC1,
               "AddDepthEquations: depth images must be CV_32FC1");
  UNSEEN_CHECK(measured.cols == in.camera.width && measured.rows == in.camera.height,
               "AddDepthEquations: measured depth is {}x{}, the camera {}x{}", measured.cols,
               measured.rows, in.camera.width, in.camera.height);
  const int width = rendered.cols, height = rendered.rows;
  if (width < 3 || height < 3) return;

  // Grid step from the rendered area, so that about max_points pixels are sampled.
  long covered = 0;
  for (int y = 0; y < height; y += 2) {
    const float* d = rendered.ptr<float>(y);
    for (int x = 0; x < width; x += 2) covered += d[x] > 0.0f;
  }
  covered *= 4;
  if (covered == 0) return;
  const int step = std::max(1, int(std::ceil(std::sqrt(double(covered) / options.max_points))));
  const double gate = options.max_distance_m * double(1 << in.level);
  const PinholeCamera& lc = in.level_camera;
  const PinholeCamera& fc = in.camera;
  const float o[3] = {float(in.origin_in_cam.x()), float(in.origin_in_cam.y()),
                      float(in.origin_in_cam.z())};
  auto back_project = [&](int bx, int by, float z) {
    const double u = bx + in.roi.x0, v = by + in.roi.y0;
    return Eigen::Vector3d((u - lc.cx) / lc.fx * z, (v - lc.cy) / lc.fy * z, z);
  };
  // Neighbours for the normal must lie on the same surface: within this depth of the point.
  const float max_step_depth = 0.02f;

  DepthCounts c;
  // The grid is fixed to the image, not to the region of interest: wherever the region is
  // placed, the same image pixels are sampled (a grid that moved with the region would
  // sample other points of the surface each round, and the alignment would jitter).
  auto first_on_grid = [step](int origin) {
    return 1 + ((step - (origin + 1) % step) % step);  // >= 1, (first + origin) % step == 0
  };
  // 1. Association: each sampled pixel's measured point (the nearest pixel where p projects
  // at full resolution).
  thread_local std::vector<DepthPair> pairs;
  pairs.clear();
  for (int y = first_on_grid(in.roi.y0); y < height - 1; y += step) {
    const float* row = rendered.ptr<float>(y);
    for (int x = first_on_grid(in.roi.x0); x < width - 1; x += step) {
      const float z = row[x];
      if (z <= 0.0f) continue;
      ++c.sampled;
      const Eigen::Vector2d pix = fc.Project(back_project(x, y, z));
      const int mx = int(std::lround(pix.x())), my = int(std::lround(pix.y()));
      if (mx < 0 || my < 0 || mx >= fc.width || my >= fc.height) continue;
      const float zm = measured.ptr<float>(my)[mx];
      if (!(zm > 0.0f) || !std::isfinite(zm)) continue;
      ++c.measured;
      const double dz = double(zm) - double(z);
      if (std::abs(dz) <= options.agree_distance_m) ++c.agreeing;
      if (dz < -options.agree_distance_m) ++c.hidden;
      float slope = 0.0f;
      const float zl = row[x - 1], zr = row[x + 1];
      const float zu = rendered.ptr<float>(y - 1)[x], zd = rendered.ptr<float>(y + 1)[x];
      if (zl > 0.0f && zr > 0.0f && zu > 0.0f && zd > 0.0f) {
        slope = 0.5f * std::hypot(zr - zl, zd - zu) / float(1 << in.level);
      }
      pairs.push_back({x, y, mx, my, z, zm, dz, slope});
    }
  }
  // A measured surface in front of the rendered one is an occluder (a hand holding the
  // object): no row, unless most of the object is behind one (the pose is behind the
  // measured surface, and every row pulls it forward). The margin is at least
  // occluder_margin_sigmas times the sensor's noise (where that is large, far from it,
  // cutting its near side only would push the object away), and on a steep surface the
  // depth it changes across occluder_slope_px pixels (what a pixel or two of misregistration
  // makes of it, with no occluder).
  const double margin = OccluderMargin(pairs, gate, measured, options);
  auto in_front = [&](const DepthPair& pair) {
    return pair.dz < -std::max(margin, options.occluder_slope_px * double(pair.slope));
  };
  long pairs_in_front = 0;
  for (const DepthPair& pair : pairs) pairs_in_front += in_front(pair);
  const bool skip_in_front = margin > 0.0 && 2 * pairs_in_front < c.measured;
  // 2. Rows.
  for (const DepthPair& pair : pairs) {
    const int x = pair.x, y = pair.y;
    const float z = pair.z;
    if (std::abs(pair.dz) > gate) continue;
    if (skip_in_front && in_front(pair)) continue;
    // Normal from central differences of the rendered surface.
    const float* row = rendered.ptr<float>(y);
    const float zl = row[x - 1], zr = row[x + 1];
    const float zu = rendered.ptr<float>(y - 1)[x], zd = rendered.ptr<float>(y + 1)[x];
    if (zl <= 0.0f || zr <= 0.0f || zu <= 0.0f || zd <= 0.0f) continue;
    if (std::abs(zl - z) > max_step_depth || std::abs(zr - z) > max_step_depth ||
        std::abs(zu - z) > max_step_depth || std::abs(zd - z) > max_step_depth) {
      continue;
    }
    const Eigen::Vector3d p = back_project(x, y, z);
    const Eigen::Vector3d tx = back_project(x + 1, y, zr) - back_project(x - 1, y, zl);
    const Eigen::Vector3d ty = back_project(x, y + 1, zd) - back_project(x, y - 1, zu);
    Eigen::Vector3d n = ty.cross(tx);
    const double norm = n.norm();
    if (!(norm > 0.0)) continue;
    n /= norm;
    if (n.dot(p) > 0.0) n = -n;  // facing the camera
    // Grazing surfaces measure badly and their normal is unreliable.
    if (-n.dot(p.normalized()) < 0.2) continue;
    const Eigen::Vector3d q = fc.Unproject(Eigen::Vector2d(pair.mx, pair.my), pair.zm);
    const float b = static_cast<float>(n.dot(q - p));
    const float pr[3] = {float(p.x()) - o[0], float(p.y()) - o[1], float(p.z()) - o[2]};
    const float nf[3] = {float(n.x()), float(n.y()), float(n.z())};
    const float a[6] = {nf[0],
                        nf[1],
                        nf[2],
                        pr[1] * nf[2] - pr[2] * nf[1],
                        pr[2] * nf[0] - pr[0] * nf[2],
                        pr[0] * nf[1] - pr[1] * nf[0]};
    out->Add(a, b, 1.0f);
    ++c.used;
  }
  *counts += c;
}

void DepthModality::AddEquations(const ModalityRound& round) {
  if (!round.measured_depth || round.measured_depth->empty()) return;
  UNSEEN_CHECK(round.virtual_image, "DepthModality: the round has no rendered depth");
  DepthModalityInput in;
  in.rendered_depth = &round.virtual_image->depth;
  in.roi = round.roi;
  in.level_camera = round.level_camera;
  in.level = round.level;
  in.measured_depth = round.measured_depth;
  in.camera = round.camera_intrinsics;
  in.origin_in_cam = round.origin_in_cam;
  AddDepthEquations(in, options_, &CameraEquations(round), &CameraCounts(round));
}

}  // namespace unseen
