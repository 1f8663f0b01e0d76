// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/select/recognition_filter.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "unseen/image/image_io.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

// Twice the signed area of a polygon (shoelace).
double SignedArea2(const std::vector<cv::Point2f>& p) {
  double a = 0.0;
  for (size_t i = 0; i < p.size(); ++i) {
    const cv::Point2f& u = p[i];
    const cv::Point2f& v = p[(i + 1) % p.size()];
    a += static_cast<double>(u.x) * v.y - static_cast<double>(v.x) * u.y;
  }
  return a;
}

// Every turn of the polygon goes the same way as `sign` (strictly convex, not twisted).
bool ConvexWithOrientation(const std::vector<cv::Point2f>& p, double sign) {
  for (size_t i = 0; i < p.size(); ++i) {
    const cv::Point2f e1 = p[(i + 1) % p.size()] - p[i];
    const cv::Point2f e2 = p[(i + 2) % p.size()] - p[(i + 1) % p.size()];
    if ((static_cast<double>(e1.x) * e2.y - static_cast<double>(e1.y) * e2.x) * sign <= 0.0) {
      return false;
    }
  }
  return true;
}

// ORB's descriptors need 31 px around a keypoint: a margin lets the reference's own
// border keep its keypoints.
constexpr int kOrbMarginPx = 32;

}  // namespace

RecognitionFilter::RecognitionFilter(std::unique_ptr<ObjectRecognizer> recognizer)
    : recognizer_(std::move(recognizer)) {
  UNSEEN_CHECK(recognizer_ != nullptr, "recognition filter: no recogniser");
}

void RecognitionFilter::Apply(const FilterFrame& frame, cv::Mat* interest) {
  UNSEEN_CHECK(frame.image.type() == CV_32FC3 && !frame.image.empty(),
               "recognition filter: the image must be CV_32FC3 BGR in [0, 1] (type {})",
               frame.image.type());
  UNSEEN_CHECK(interest->type() == CV_32FC1 && interest->size() == frame.image.size(),
               "recognition filter: the interest map must be CV_32FC1 of the image's {}x{} "
               "pixels",
               frame.image.cols, frame.image.rows);
  if (cv::countNonZero(*interest > 0.0f) == 0) return;
  cv::Mat bgr8;
  frame.image.convertTo(bgr8, CV_8UC3, 255.0);
  std::vector<Detection> detections = recognizer_->Detect(bgr8);
  for (Detection& d : detections) d.score = d.score > 0.0 ? std::min(d.score, 1.0) : 0.0;
  // Drawn from the lowest score up, so a pixel keeps the highest of those covering it.
  std::stable_sort(detections.begin(), detections.end(),
                   [](const Detection& a, const Detection& b) { return a.score < b.score; });
  constexpr int kShift = 4;  // sub-pixel vertices, 1/16 px
  constexpr float kLimit = 1 << 20;
  cv::Mat calc(frame.image.size(), CV_32FC1, cv::Scalar(0.0f));
  for (const Detection& d : detections) {
    if (d.polygon.size() < 3 || d.score <= 0.0) continue;
    std::vector<cv::Point> vertices;
    for (const cv::Point2f& p : d.polygon) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) break;
      vertices.emplace_back(static_cast<int>(std::lround(std::clamp(p.x, -kLimit, kLimit) * 16)),
                            static_cast<int>(std::lround(std::clamp(p.y, -kLimit, kLimit) * 16)));
    }
    if (vertices.size() != d.polygon.size()) continue;
    cv::fillPoly(calc, std::vector<std::vector<cv::Point>>{vertices},
                 cv::Scalar(static_cast<float>(d.score)), cv::LINE_8, kShift);
  }
  cv::multiply(*interest, calc, *interest);
}

void FeatureRecognizerOptions::Check() const {
  UNSEEN_CHECK(reference_features >= 10 && reference_features <= 100000,
               "feature recognizer: reference_features {} not in [10, 100000]", reference_features);
  UNSEEN_CHECK(frame_features >= 10 && frame_features <= 100000,
               "feature recognizer: frame_features {} not in [10, 100000]", frame_features);
  UNSEEN_CHECK(ratio > 0.0 && ratio <= 1.0, "feature recognizer: ratio {} not in (0, 1]", ratio);
  UNSEEN_CHECK(ransac_threshold_px > 0.0 && ransac_threshold_px <= 100.0,
               "feature recognizer: ransac_threshold_px {} not in (0, 100]", ransac_threshold_px);
  UNSEEN_CHECK(min_inliers >= 4, "feature recognizer: min_inliers {} must be >= 4 (a homography)",
               min_inliers);
  UNSEEN_CHECK(min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0,
               "feature recognizer: min_inlier_ratio {} not in [0, 1]", min_inlier_ratio);
  UNSEEN_CHECK(full_score_inliers >= 1, "feature recognizer: full_score_inliers {} must be >= 1",
               full_score_inliers);
  UNSEEN_CHECK(min_side_px >= 0.0 && std::isfinite(min_side_px),
               "feature recognizer: min_side_px {} must be >= 0", min_side_px);
  UNSEEN_CHECK(min_area_px2 >= 0.0 && std::isfinite(min_area_px2),
               "feature recognizer: min_area_px2 {} must be >= 0", min_area_px2);
  UNSEEN_CHECK(max_area_fraction > 0.0 && max_area_fraction <= 1.0,
               "feature recognizer: max_area_fraction {} not in (0, 1]", max_area_fraction);
  UNSEEN_CHECK(max_area_change >= 1.0 && std::isfinite(max_area_change),
               "feature recognizer: max_area_change {} must be >= 1", max_area_change);
}

FeatureRecognizer::FeatureRecognizer(const FeatureRecognizerOptions& options) : options_(options) {
  options_.Check();
  reference_orb_ = cv::ORB::create(options_.reference_features);
  frame_orb_ = cv::ORB::create(options_.frame_features);
}

void FeatureRecognizer::AddReference(const cv::Mat& image, cv::Rect rect, const std::string& what) {
  const cv::Mat bgr = ToFloatBgr(image, what);
  if (rect.empty()) rect = cv::Rect(0, 0, bgr.cols, bgr.rows);
  UNSEEN_CHECK(rect.x >= 0 && rect.y >= 0 && rect.width > 0 && rect.height > 0 &&
                   static_cast<int64_t>(rect.x) + rect.width <= bgr.cols &&
                   static_cast<int64_t>(rect.y) + rect.height <= bgr.rows,
               "{}: the object's rectangle [{}, {}, {}, {}] is not inside the {}x{} image", what,
               rect.x, rect.y, rect.width, rect.height, bgr.cols, bgr.rows);
  cv::Mat grey_float, grey, padded;
  cv::cvtColor(bgr, grey_float, cv::COLOR_BGR2GRAY);
  grey_float.convertTo(grey, CV_8U, 255.0);
  cv::copyMakeBorder(grey, padded, kOrbMarginPx, kOrbMarginPx, kOrbMarginPx, kOrbMarginPx,
                     cv::BORDER_REFLECT_101);
  cv::Mat mask(padded.size(), CV_8UC1, cv::Scalar(0));
  mask(rect + cv::Point(kOrbMarginPx, kOrbMarginPx)).setTo(255);
  Reference ref;
  reference_orb_->detectAndCompute(padded, mask, ref.keypoints, ref.descriptors);
  UNSEEN_CHECK(static_cast<int>(ref.keypoints.size()) >= options_.min_inliers,
               "{}: {} ORB keypoints in the object's rectangle, fewer than min_inliers {} (too "
               "small or too little texture)",
               what, ref.keypoints.size(), options_.min_inliers);
  for (cv::KeyPoint& k : ref.keypoints) k.pt -= cv::Point2f(kOrbMarginPx, kOrbMarginPx);
  const cv::Rect2f r(rect);
  ref.outline = {r.tl(), cv::Point2f(r.x + r.width, r.y), r.br(), cv::Point2f(r.x, r.y + r.height)};
  ref.area_px2 = r.area();
  references_.push_back(std::move(ref));
}

std::vector<Detection> FeatureRecognizer::Detect(const cv::Mat& bgr8) {
  UNSEEN_CHECK(bgr8.type() == CV_8UC3 && !bgr8.empty(),
               "feature recognizer: the image must be CV_8UC3 BGR (type {})", bgr8.type());
  std::vector<Detection> detections;
  if (references_.empty()) return detections;
  cv::Mat grey;
  cv::cvtColor(bgr8, grey, cv::COLOR_BGR2GRAY);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  frame_orb_->detectAndCompute(grey, cv::noArray(), keypoints, descriptors);
  if (static_cast<int>(keypoints.size()) < options_.min_inliers) return detections;
  const double image_area = static_cast<double>(bgr8.cols) * bgr8.rows;

  for (const Reference& ref : references_) {
    std::vector<std::vector<cv::DMatch>> knn;
    matcher_.knnMatch(ref.descriptors, descriptors, knn, 2);
    std::vector<cv::Point2f> from, to;
    for (const std::vector<cv::DMatch>& m : knn) {
      if (m.size() == 2 && m[0].distance < options_.ratio * m[1].distance) {
        from.push_back(ref.keypoints[m[0].queryIdx].pt);
        to.push_back(keypoints[m[0].trainIdx].pt);
      }
    }
    if (static_cast<int>(from.size()) < options_.min_inliers) continue;
    std::vector<uchar> inlier;
    const cv::Mat frame_from_ref =
        cv::findHomography(from, to, cv::RANSAC, options_.ransac_threshold_px, inlier, 2000, 0.995);
    if (frame_from_ref.empty() || !cv::checkRange(frame_from_ref)) continue;
    const int inliers = cv::countNonZero(inlier);
    if (inliers < options_.min_inliers ||
        inliers < options_.min_inlier_ratio * static_cast<double>(from.size())) {
      continue;
    }
    // The outline must stay in front of the homography's plane (w > 0 at every corner).
    const cv::Matx33d h(frame_from_ref);
    bool in_front = true;
    for (const cv::Point2f& p : ref.outline)
      in_front &= h(2, 0) * p.x + h(2, 1) * p.y + h(2, 2) > 0.0;
    if (!in_front) continue;
    std::vector<cv::Point2f> outline;
    cv::perspectiveTransform(ref.outline, outline, frame_from_ref);
    const double area = 0.5 * std::abs(SignedArea2(outline));
    bool sane = ConvexWithOrientation(outline, SignedArea2(ref.outline)) &&
                area >= options_.min_area_px2 && area <= options_.max_area_fraction * image_area &&
                area * options_.max_area_change >= ref.area_px2 &&
                area <= options_.max_area_change * ref.area_px2;
    for (size_t i = 0; i < outline.size() && sane; ++i) {
      sane = cv::norm(outline[(i + 1) % outline.size()] - outline[i]) >= options_.min_side_px;
    }
    if (!sane) continue;
    detections.push_back({std::move(outline), std::min(1.0, static_cast<double>(inliers) /
                                                                options_.full_score_inliers)});
  }
  return detections;
}

}  // namespace unseen
