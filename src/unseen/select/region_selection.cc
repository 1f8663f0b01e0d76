// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/select/region_selection.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "unseen/util/error.h"

namespace unseen {

void RegionSelectionOptions::Check() const {
  UNSEEN_CHECK(min_interest >= 0.0 && min_interest < 1.0,
               "selection.min_interest {} must be in [0, 1)", min_interest);
  UNSEEN_CHECK(min_texturedness >= 0.0 && std::isfinite(min_texturedness),
               "selection.min_texturedness {} must be >= 0", min_texturedness);
  UNSEEN_CHECK(min_area_px >= 1, "selection.min_area_px {} must be >= 1", min_area_px);
  UNSEEN_CHECK(min_interest_share >= 0.0 && min_interest_share <= 1.0,
               "selection.min_interest_share {} must be in [0, 1]", min_interest_share);
  UNSEEN_CHECK(min_mean_interest >= 0.0 && min_mean_interest <= 1.0,
               "selection.min_mean_interest {} must be in [0, 1]", min_mean_interest);
  UNSEEN_CHECK(min_total_interest >= 0.0 && std::isfinite(min_total_interest),
               "selection.min_total_interest {} must be >= 0", min_total_interest);
  UNSEEN_CHECK(min_size_m >= 0.0 && max_size_m > min_size_m && std::isfinite(max_size_m),
               "selection: size range [{}, {}] m is empty", min_size_m, max_size_m);
}

RegionSelection SelectRegion(const cv::Mat& labels, const cv::Mat& interest,
                             const cv::Mat& texturedness, const cv::Mat& depth,
                             const PinholeCamera& camera, const RegionSelectionOptions& options) {
  options.Check();
  UNSEEN_CHECK(
      labels.type() == CV_32SC1 && interest.type() == CV_32FC1 && labels.size() == interest.size(),
      "SelectRegion: labels (CV_32SC1) and interest (CV_32FC1) must be of one size");
  UNSEEN_CHECK(texturedness.empty() ||
                   (texturedness.type() == CV_32FC1 && texturedness.size() == labels.size()),
               "SelectRegion: texturedness must be CV_32FC1 of the labels' size or empty");
  UNSEEN_CHECK(depth.empty() || (depth.type() == CV_32FC1 && depth.size() == labels.size()),
               "SelectRegion: depth must be CV_32FC1 of the labels' size or empty");
  double max_label = 0.0;
  cv::minMaxLoc(labels, nullptr, &max_label);
  RegionSelection out;
  out.regions.resize(static_cast<size_t>(std::max(0.0, max_label)));
  std::vector<double> depth_sum(out.regions.size(), 0.0);
  for (size_t i = 0; i < out.regions.size(); ++i) {
    out.regions[i].label = static_cast<int>(i) + 1;
    out.regions[i].box = PixelRect{labels.cols, labels.rows, 0, 0};
  }
  for (int y = 0; y < labels.rows; ++y) {
    const int* l = labels.ptr<int>(y);
    const float* s = interest.ptr<float>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (l[x] <= 0) continue;
      RegionCandidate& r = out.regions[l[x] - 1];
      ++r.total_area;
      r.box = PixelRect{std::min(r.box.x0, x), std::min(r.box.y0, y), std::max(r.box.x1, x + 1),
                        std::max(r.box.y1, y + 1)};
      if (!(s[x] > options.min_interest)) continue;  // Z: pixels of interest
      ++r.interest_area;
      r.total_interest += s[x];
      if (!texturedness.empty() && !(texturedness.at<float>(y, x) > options.min_texturedness)) {
        continue;
      }
      const float d = depth.empty() ? 0.0f : depth.at<float>(y, x);
      if (d > 0.0f) {  // W: where the depth is reliable
        ++r.depth_area;
        depth_sum[l[x] - 1] += d;
      }
    }
  }
  double best = -1.0;
  for (size_t i = 0; i < out.regions.size(); ++i) {
    RegionCandidate& r = out.regions[i];
    if (r.total_area == 0) {
      r.rejected = "no pixels";
      continue;
    }
    r.mean_interest = r.total_interest / r.total_area;
    if (r.depth_area > 0) {
      r.mean_depth_m = depth_sum[i] / r.depth_area;
      r.width_m = r.box.width() * r.mean_depth_m / camera.fx;
      r.height_m = r.box.height() * r.mean_depth_m / camera.fy;
    }
    if (r.total_area < options.min_area_px) {
      r.rejected = fmt::format("area {} px < {}", r.total_area, options.min_area_px);
    } else if (double(r.interest_area) / r.total_area <= options.min_interest_share) {
      r.rejected = fmt::format("share of interest {:.2f} <= {}",
                               double(r.interest_area) / r.total_area, options.min_interest_share);
    } else if (r.mean_interest < options.min_mean_interest) {
      r.rejected =
          fmt::format("mean interest {:.2f} < {}", r.mean_interest, options.min_mean_interest);
    } else if (r.total_interest < options.min_total_interest) {
      r.rejected =
          fmt::format("total interest {:.0f} < {}", r.total_interest, options.min_total_interest);
    } else if (!depth.empty() && r.depth_area == 0) {
      r.rejected = "no depth on its textured pixels of interest";
    } else if (!depth.empty() && (std::min(r.width_m, r.height_m) < options.min_size_m ||
                                  std::max(r.width_m, r.height_m) > options.max_size_m)) {
      r.rejected = fmt::format("size {:.3f} x {:.3f} m outside [{}, {}]", r.width_m, r.height_m,
                               options.min_size_m, options.max_size_m);
    } else {
      r.candidate = true;
      const double rank = options.rank_by_total_interest ? r.total_interest : r.mean_interest;
      if (rank > best) {
        best = rank;
        out.selected = static_cast<int>(i);
      }
    }
  }
  return out;
}

cv::Mat InterestRegions(const cv::Mat& interest, double min_interest, int close_px) {
  UNSEEN_CHECK(interest.type() == CV_32FC1, "InterestRegions: interest must be CV_32FC1");
  UNSEEN_CHECK(close_px >= 1 && close_px % 2 == 1, "InterestRegions: close_px {} must be odd",
               close_px);
  cv::Mat of_interest = interest > min_interest;
  if (close_px > 1) {
    cv::morphologyEx(of_interest, of_interest, cv::MORPH_CLOSE,
                     cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(close_px, close_px)));
  }
  cv::Mat labels;
  cv::connectedComponents(of_interest, labels, 8, CV_32S);
  return labels;
}

}  // namespace unseen
