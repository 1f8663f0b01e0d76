// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/apps/reconfiguration_plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <string>

#include "unseen/util/error.h"

namespace unseen {

namespace {

const cv::Scalar kVariantColour[kNumVariants] = {{40, 40, 220}, {200, 110, 20}, {140, 140, 140}};

// Maps top-view metres into a square panel, z upwards.
struct TopViewMap {
  Eigen::Vector2d lo, hi;
  int size_px = 600;
  cv::Point operator()(const Eigen::Vector2d& p) const {
    const double scale = (size_px - 40) / std::max(hi.x() - lo.x(), hi.y() - lo.y());
    return {static_cast<int>(20 + (p.x() - lo.x()) * scale),
            static_cast<int>(size_px - 20 - (p.y() - lo.y()) * scale)};
  }
  int Pixels(double metres) const {
    return static_cast<int>(metres * (size_px - 40) / std::max(hi.x() - lo.x(), hi.y() - lo.y()));
  }
};

Eigen::Vector2d TopView(const Rigid3d& world_from_obj) {
  return {world_from_obj.translation().x(), world_from_obj.translation().z()};
}

void DrawTopView(const ReconfigurationConfig& config, const ReconfigurationResult& result,
                 int variant, const TopViewMap& map, const ReconfigurationPlotOptions& options,
                 cv::Mat panel) {
  panel.setTo(cv::Scalar::all(255));
  for (const Column& c : config.columns) {
    cv::circle(panel, map(c.centre_m), std::max(2, map.Pixels(c.radius_m)), {90, 90, 90},
               cv::FILLED, cv::LINE_AA);
  }
  // The tracking rig.
  for (int i = 0; i < config.tracking_cameras; ++i) {
    const double x =
        config.tracking_cameras == 1
            ? 0.5 * (config.tracking_from_x_m + config.tracking_to_x_m)
            : config.tracking_from_x_m + i * (config.tracking_to_x_m - config.tracking_from_x_m) /
                                             (config.tracking_cameras - 1);
    cv::rectangle(panel, map({x, 0.0}) - cv::Point(3, 3), map({x, 0.0}) + cv::Point(3, 3),
                  {0, 120, 0}, cv::FILLED);
  }
  std::vector<cv::Point> truth, tracked;
  for (const ReconfigurationFrame& f : result.frames) {
    truth.push_back(map(TopView(f.true_world_from_obj)));
    tracked.push_back(map(TopView(f.tracked_world_from_obj)));
  }
  cv::polylines(panel, truth, false, {0, 0, 0}, 2, cv::LINE_AA);
  if (variant == kTrackedPoses) cv::polylines(panel, tracked, false, {40, 40, 220}, 1, cv::LINE_AA);
  // Cameras at regular frames, later ones darker; the default poses in grey.
  const int frames = static_cast<int>(result.frames.size());
  for (size_t i = 0; i < config.cameras.size(); ++i) {
    const StageCamera& cam = config.cameras[i];
    std::vector<int> shown;
    for (int k = 0; k < frames; k += options.camera_every_frames) shown.push_back(k);
    for (size_t s = 0; s <= shown.size(); ++s) {
      const bool home = s == shown.size();
      const TopViewCamera view =
          cam.ViewAt(home ? cam.home : result.frames[shown[s]].states[variant][i]);
      const double shade = home ? 0.0 : 1.0 - 0.8 * s / std::max<size_t>(1, shown.size() - 1);
      const cv::Scalar colour =
          home ? cv::Scalar(170, 170, 170) : kVariantColour[variant] * (1.0 - 0.6 * (1.0 - shade));
      for (double side : {-0.5, 0.5}) {
        const Eigen::Vector2d end =
            view.position_m +
            options.ray_length_m *
                HeadingDirection(view.heading_rad + side * view.horizontal_fov_rad);
        cv::line(panel, map(view.position_m), map(end), colour, 1, cv::LINE_AA);
      }
      cv::circle(panel, map(view.position_m), 4, colour, cv::FILLED, cv::LINE_AA);
      if (!home && s + 1 == shown.size()) {
        cv::putText(panel, cam.name, map(view.position_m) + cv::Point(6, -6),
                    cv::FONT_HERSHEY_SIMPLEX, 0.4, {0, 0, 0}, 1, cv::LINE_AA);
      }
    }
  }
  cv::putText(
      panel,
      fmt::format("top view, reconfigured on {} poses (cameras every {} frames)",
                  variant == kTrackedPoses ? "tracked" : "true", options.camera_every_frames),
      {8, 16}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0}, 1, cv::LINE_AA);
}

void DrawCurves(const ReconfigurationConfig& config, const ReconfigurationResult& result,
                int camera, cv::Mat panel) {
  panel.setTo(cv::Scalar::all(255));
  const int w = panel.cols, h = panel.rows, left = 40, bottom = 20, top = 18;
  const int frames = static_cast<int>(result.frames.size());
  const auto at = [&](int k, double v) {
    return cv::Point(left + (w - left - 10) * k / std::max(1, frames - 1),
                     top + static_cast<int>((h - top - bottom) * (1.0 - v)));
  };
  for (double v : {0.0, 0.5, 1.0}) {
    cv::line(panel, at(0, v), at(frames - 1, v), {220, 220, 220}, 1);
    cv::putText(panel, fmt::format("{:.1f}", v), at(0, v) + cv::Point(-32, 4),
                cv::FONT_HERSHEY_SIMPLEX, 0.35, {0, 0, 0}, 1, cv::LINE_AA);
  }
  for (int v = kNumVariants - 1; v >= 0; --v) {
    std::vector<cv::Point> line;
    for (int k = 0; k < frames; ++k)
      line.push_back(at(k, result.frames[k].visibility[v][camera].value));
    cv::polylines(panel, line, false, kVariantColour[v], v == kTrackedPoses ? 1 : 2, cv::LINE_AA);
  }
  cv::putText(panel,
              fmt::format("{}: visibility V (5.1) over frames 0-{}; red tracked poses {:.3f}, blue "
                          "true poses {:.3f}, grey fixed {:.3f}",
                          config.cameras[camera].name, frames - 1,
                          result.camera_mean_visibility[kTrackedPoses][camera],
                          result.camera_mean_visibility[kTruePoses][camera],
                          result.camera_mean_visibility[kFixedCameras][camera]),
              {left, 13}, cv::FONT_HERSHEY_SIMPLEX, 0.4, {0, 0, 0}, 1, cv::LINE_AA);
}

}  // namespace

void ReconfigurationPlotOptions::Check() const {
  UNSEEN_CHECK(
      top_view_px >= 100 && curve_height_px >= 60 && camera_every_frames >= 1 && ray_length_m > 0,
      "reconfiguration plot: top_view_px ({}) >= 100, curve_height_px ({}) >= 60, "
      "camera_every_frames ({}) >= 1 and ray_length_m ({}) > 0 needed",
      top_view_px, curve_height_px, camera_every_frames, ray_length_m);
}

cv::Mat DrawReconfigurationPlot(const ReconfigurationConfig& config,
                                const ReconfigurationResult& result,
                                const ReconfigurationPlotOptions& options) {
  options.Check();
  UNSEEN_CHECK(!result.frames.empty(), "reconfiguration plot: the result has no frames");
  // Bounds: everything drawn.
  TopViewMap map;
  map.size_px = options.top_view_px;
  map.lo = map.hi = TopView(result.frames[0].true_world_from_obj);
  const auto include = [&](const Eigen::Vector2d& p, double margin) {
    map.lo = map.lo.cwiseMin(p - Eigen::Vector2d::Constant(margin));
    map.hi = map.hi.cwiseMax(p + Eigen::Vector2d::Constant(margin));
  };
  for (const Column& c : config.columns) include(c.centre_m, c.radius_m);
  include({config.tracking_from_x_m, 0.0}, 0.05);
  include({config.tracking_to_x_m, 0.0}, 0.05);
  for (const StageCamera& c : config.cameras) {
    include(c.ViewAt({c.rail_min_m, 0.0}).position_m, 0.1);
    include(c.ViewAt({c.rail_max_m, 0.0}).position_m, 0.1);
  }
  const int n = static_cast<int>(config.cameras.size());
  const int width = 2 * options.top_view_px;
  cv::Mat plot(options.top_view_px + n * options.curve_height_px, width, CV_8UC3,
               cv::Scalar::all(255));
  DrawTopView(config, result, kTruePoses, map, options,
              plot(cv::Rect(0, 0, options.top_view_px, options.top_view_px)));
  DrawTopView(config, result, kTrackedPoses, map, options,
              plot(cv::Rect(options.top_view_px, 0, options.top_view_px, options.top_view_px)));
  cv::line(plot, {options.top_view_px, 0}, {options.top_view_px, options.top_view_px}, {0, 0, 0},
           1);
  for (int i = 0; i < n; ++i) {
    DrawCurves(config, result, i,
               plot(cv::Rect(0, options.top_view_px + i * options.curve_height_px, width,
                             options.curve_height_px)));
  }
  return plot;
}

}  // namespace unseen
