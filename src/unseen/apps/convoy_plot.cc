// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/apps/convoy_plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "unseen/util/error.h"

namespace unseen {

namespace {

const cv::Scalar kLeadColor(200, 90, 20);      // blue
const cv::Scalar kFollowerColor(30, 30, 220);  // red
const cv::Scalar kTrackedColor(40, 170, 40);   // green
const cv::Scalar kAxisColor(90, 90, 90);
const cv::Scalar kTextColor(20, 20, 20);

void Text(cv::Mat* image, const std::string& text, cv::Point at, double scale = 0.45,
          const cv::Scalar& color = kTextColor) {
  cv::putText(*image, text, at, cv::FONT_HERSHEY_SIMPLEX, scale, color, 1, cv::LINE_AA);
}

// Top view in `box`, millimetres, equal scales, y up.
void DrawTopView(const ConvoyResult& r, const cv::Rect& box, cv::Mat* image) {
  Eigen::Vector2d min = r.lead_path.front().position, max = min;
  const auto extend = [&](const Eigen::Vector2d& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  };
  for (const PlanarPose& p : r.lead_path) extend(p.position);
  for (const ConvoyFrame& f : r.frames) extend(f.follower.pose.position);
  const double margin = 0.05 * std::max(max.x() - min.x(), max.y() - min.y()) + 1e-3;
  min.array() -= margin;
  max.array() += margin;
  const double scale =
      std::min((box.width - 60) / (max.x() - min.x()), (box.height - 60) / (max.y() - min.y()));
  const auto px = [&](const Eigen::Vector2d& p) {
    return cv::Point(
        box.x + 50 + static_cast<int>(std::lround((p.x() - min.x()) * scale)),
        box.y + box.height - 30 - static_cast<int>(std::lround((p.y() - min.y()) * scale)));
  };
  cv::rectangle(*image, px(min), px(max), kAxisColor, 1);
  Text(image,
       fmt::format("top view: x {:.0f}..{:.0f} mm, y {:.0f}..{:.0f} mm", 1e3 * min.x(),
                   1e3 * max.x(), 1e3 * min.y(), 1e3 * max.y()),
       px(min) + cv::Point(0, 18));
  std::vector<cv::Point> lead, follower;
  for (const PlanarPose& p : r.lead_path) lead.push_back(px(p.position));
  for (const ConvoyFrame& f : r.frames) follower.push_back(px(f.follower.pose.position));
  cv::polylines(*image, lead, false, kLeadColor, 2, cv::LINE_AA);
  cv::polylines(*image, follower, false, kFollowerColor, 1, cv::LINE_AA);
  for (const ConvoyFrame& f : r.frames) {
    if (f.tracked && f.frame % 3 == 0)
      cv::circle(*image, px(f.lead_tracked.position), 1, kTrackedColor, -1);
  }
  const cv::Point legend(px(max).x - 140, px(max).y + 20);  // top right
  Text(image, "lead (true)", legend, 0.5, kLeadColor);
  Text(image, "follower", legend + cv::Point(0, 20), 0.5, kFollowerColor);
  Text(image, "lead (tracked)", legend + cv::Point(0, 40), 0.5, kTrackedColor);
}

struct Series {
  std::string label;
  cv::Scalar color;
  std::function<double(const ConvoyFrame&)> value_mm;  // NaN: no value
};

// Time plot of `series` in `box` with a zero line and the value range.
void DrawTimePlot(const ConvoyResult& r, const std::string& title,
                  const std::vector<Series>& series, const cv::Rect& box, cv::Mat* image) {
  double lo = 0.0, hi = 0.0;
  for (const Series& s : series) {
    for (const ConvoyFrame& f : r.frames) {
      const double v = s.value_mm(f);
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    }
  }
  if (hi - lo < 1e-6) hi = lo + 1.0;
  const cv::Rect area(box.x + 60, box.y + 22, box.width - 70, box.height - 44);
  const double t_max = std::max(r.frames.back().time_s, 1e-6);
  const auto px = [&](double t, double v) {
    return cv::Point(area.x + static_cast<int>(std::lround(t / t_max * area.width)),
                     area.y + static_cast<int>(std::lround((hi - v) / (hi - lo) * area.height)));
  };
  cv::rectangle(*image, area, kAxisColor, 1);
  cv::line(*image, px(0, 0), px(t_max, 0), kAxisColor, 1);
  Text(image, title, cv::Point(box.x + 60, box.y + 16), 0.5);
  Text(image, fmt::format("{:+.2f}", hi), cv::Point(box.x, area.y + 10));
  Text(image, fmt::format("{:+.2f}", lo), cv::Point(box.x, area.y + area.height));
  Text(image, fmt::format("{:.1f} s", t_max),
       cv::Point(area.x + area.width - 40, area.y + area.height + 16));
  int legend_x = box.x + box.width - 10;
  for (auto it = series.rbegin(); it != series.rend(); ++it) {
    legend_x -= 10 + 8 * static_cast<int>(it->label.size());
    Text(image, it->label, cv::Point(legend_x, box.y + 16), 0.45, it->color);
  }
  for (const Series& s : series) {
    std::vector<cv::Point> line;
    const auto flush = [&] {
      if (line.size() > 1) cv::polylines(*image, line, false, s.color, 1, cv::LINE_AA);
      line.clear();
    };
    for (const ConvoyFrame& f : r.frames) {
      const double v = s.value_mm(f);
      if (!std::isfinite(v)) {
        flush();
        continue;
      }
      line.push_back(px(f.time_s, v));
    }
    flush();
  }
}

}  // namespace

void ConvoyPlotOptions::Check() const {
  UNSEEN_CHECK(width_px >= 400 && height_px >= 300,
               "convoy plot: size {}x{} must be at least 400x300", width_px, height_px);
}

cv::Mat DrawConvoyPlot(const ConvoyResult& result, const ConvoyPlotOptions& options) {
  options.Check();
  UNSEEN_CHECK(!result.frames.empty() && !result.lead_path.empty(),
               "DrawConvoyPlot: the run has no frames");
  cv::Mat image(options.height_px, options.width_px, CV_8UC3, cv::Scalar(255, 255, 255));
  const int left = options.width_px * 2 / 5;
  DrawTopView(result, cv::Rect(0, 0, left, options.height_px), &image);
  const double nan = std::nan("");
  const int h = options.height_px / 3;
  const int w = options.width_px - left;
  DrawTimePlot(result, "separation error (mm)",
               {{"separation", kFollowerColor,
                 [](const ConvoyFrame& f) { return 1e3 * f.separation_error_m; }}},
               cv::Rect(left, 0, w, h), &image);
  DrawTimePlot(
      result, "tracking error (mm)",
      {{"x", kLeadColor,
        [nan](const ConvoyFrame& f) { return f.tracked ? 1e3 * f.tracking_error_m.x() : nan; }},
       {"y", kTrackedColor,
        [nan](const ConvoyFrame& f) { return f.tracked ? 1e3 * f.tracking_error_m.y() : nan; }}},
      cv::Rect(left, h, w, h), &image);
  DrawTimePlot(
      result, "cross-track error (mm)",
      {{"cross-track", kFollowerColor, [](const ConvoyFrame& f) { return 1e3 * f.cross_track_m; }}},
      cv::Rect(left, 2 * h, w, options.height_px - 2 * h), &image);
  return image;
}

void SaveConvoyPlot(const std::string& path, const ConvoyResult& result,
                    const ConvoyPlotOptions& options) {
  const cv::Mat image = DrawConvoyPlot(result, options);
  bool ok = false;
  try {
    ok = cv::imwrite(path, image);
  } catch (const cv::Exception& e) {
    ThrowError("{}: cannot write the convoy plot: {}", path, e.what());
  }
  UNSEEN_CHECK(ok, "{}: cannot write the convoy plot", path);
}

}  // namespace unseen
