// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/select/motion_segmentation.h"

#include <algorithm>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "unseen/util/error.h"

namespace unseen {
namespace {

// Union-find over block indices (path halving, union by index).
int Find(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

void Join(std::vector<int>& parent, int a, int b) {
  a = Find(parent, a);
  b = Find(parent, b);
  if (a != b) parent[std::max(a, b)] = std::min(a, b);
}

float Median(std::vector<float> values) {
  if (values.empty()) return 0.0f;
  const auto middle = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

}  // namespace

void MotionSegmentationOptions::Check() const {
  UNSEEN_CHECK(block_px >= 2 && block_px <= 64, "motion segmentation: block_px {} not in [2, 64]",
               block_px);
  UNSEEN_CHECK(min_motion_px >= 0.0, "motion segmentation: min_motion_px {} must be >= 0",
               min_motion_px);
  UNSEEN_CHECK(max_difference_px >= 0.0, "motion segmentation: max_difference_px {} must be >= 0",
               max_difference_px);
  UNSEEN_CHECK(relative_difference >= 0.0 && relative_difference <= 2.0,
               "motion segmentation: relative_difference {} not in [0, 2]", relative_difference);
  UNSEEN_CHECK(min_blocks >= 1, "motion segmentation: min_blocks {} must be >= 1", min_blocks);
  UNSEEN_CHECK(min_texture >= 0.0, "motion segmentation: min_texture {} must be >= 0", min_texture);
  UNSEEN_CHECK(min_interest_share >= 0.0 && min_interest_share <= 1.0,
               "motion segmentation: min_interest_share {} not in [0, 1]", min_interest_share);
}

MotionSegmenter::MotionSegmenter(const MotionSegmentationOptions& options)
    : options_((options.Check(), options)),
      dis_(cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_FAST)) {}

PixelRect MotionSegmenter::ObjectBox(const PixelRect& region_box) const {
  const int inset = options_.block_px / 2;
  if (region_box.width() <= 2 * inset + 2 || region_box.height() <= 2 * inset + 2) {
    return region_box;
  }
  return region_box.Grow(-inset);
}

cv::Mat MotionSegmenter::Segment(const cv::Mat& image, const cv::Mat& interest) {
  UNSEEN_CHECK(image.type() == CV_32FC3 || image.type() == CV_8UC3,
               "motion segmentation: the image must be CV_32FC3 or CV_8UC3 (type {})",
               image.type());
  UNSEEN_CHECK(interest.empty() || (interest.type() == CV_32FC1 && interest.size() == image.size()),
               "motion segmentation: the interest map must be CV_32FC1 of the image's size");
  UNSEEN_CHECK(previous_.empty() || previous_.size() == image.size(),
               "motion segmentation: frame of {}x{} after frames of {}x{}", image.cols, image.rows,
               previous_.cols, previous_.rows);
  cv::Mat grey;
  if (image.type() == CV_8UC3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else {
    cv::Mat grey_float;
    cv::cvtColor(image, grey_float, cv::COLOR_BGR2GRAY);
    grey_float.convertTo(grey, CV_8U, 255.0);
  }
  cv::Mat labels(image.size(), CV_32SC1, cv::Scalar(0));
  num_regions_ = 0;
  if (previous_.empty()) {
    previous_ = grey;
    return labels;
  }
  dis_->calc(previous_, grey, flow_);
  previous_ = grey;
  cv::Mat grey_unit, texture;
  grey.convertTo(grey_unit, CV_32F, 1.0 / 255.0);
  cv::cornerMinEigenVal(grey_unit, texture, 3, 3);

  // Each block's mean flow and share of interest.
  const int b = options_.block_px;
  const int cols = (image.cols + b - 1) / b, rows = (image.rows + b - 1) / b;
  const int n = cols * rows;
  std::vector<cv::Vec2f> motion(n, cv::Vec2f(0, 0));
  std::vector<float> interest_share(n, 1.0f);
  std::vector<float> block_texture(n, 0.0f);
  for (int by = 0; by < rows; ++by) {
    for (int bx = 0; bx < cols; ++bx) {
      const cv::Rect rect = cv::Rect(bx * b, by * b, b, b) & cv::Rect(0, 0, image.cols, image.rows);
      const cv::Scalar mean = cv::mean(flow_(rect));
      motion[by * cols + bx] = cv::Vec2f(static_cast<float>(mean[0]), static_cast<float>(mean[1]));
      block_texture[by * cols + bx] = static_cast<float>(cv::mean(texture(rect))[0]);
      if (!interest.empty()) {
        interest_share[by * cols + bx] =
            static_cast<float>(cv::countNonZero(interest(rect) > 0.5f)) / rect.area();
      }
    }
  }
  if (options_.remove_dominant_motion) {
    std::vector<float> xs(n), ys(n);
    for (int i = 0; i < n; ++i) {
      xs[i] = motion[i][0];
      ys[i] = motion[i][1];
    }
    const cv::Vec2f dominant(Median(xs), Median(ys));
    for (cv::Vec2f& m : motion) m -= dominant;
  }

  std::vector<char> moving(n);
  for (int i = 0; i < n; ++i) {
    moving[i] = cv::norm(motion[i]) > options_.min_motion_px &&
                interest_share[i] >= options_.min_interest_share &&
                block_texture[i] > options_.min_texture;
  }
  const auto alike = [&](int i, int j) {
    const double difference = cv::norm(motion[i] - motion[j]);
    const double speed = std::max(cv::norm(motion[i]), cv::norm(motion[j]));
    return difference < options_.max_difference_px ||
           difference < options_.relative_difference * speed;
  };
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (int by = 0; by < rows; ++by) {
    for (int bx = 0; bx < cols; ++bx) {
      const int i = by * cols + bx;
      if (!moving[i]) continue;
      if (bx + 1 < cols && moving[i + 1] && alike(i, i + 1)) Join(parent, i, i + 1);
      if (by + 1 < rows && moving[i + cols] && alike(i, i + cols)) Join(parent, i, i + cols);
    }
  }
  std::vector<int> size(n, 0);
  for (int i = 0; i < n; ++i) {
    if (moving[i]) ++size[Find(parent, i)];
  }
  std::vector<int> label_of_root(n, 0);
  for (int i = 0; i < n; ++i) {
    if (moving[i] && Find(parent, i) == i && size[i] >= options_.min_blocks) {
      label_of_root[i] = ++num_regions_;
    }
  }
  for (int by = 0; by < rows; ++by) {
    for (int bx = 0; bx < cols; ++bx) {
      const int i = by * cols + bx;
      if (!moving[i]) continue;
      const int label = label_of_root[Find(parent, i)];
      if (label == 0) continue;
      const cv::Rect rect = cv::Rect(bx * b, by * b, b, b) & cv::Rect(0, 0, image.cols, image.rows);
      labels(rect).setTo(label);
    }
  }
  return labels;
}

}  // namespace unseen
