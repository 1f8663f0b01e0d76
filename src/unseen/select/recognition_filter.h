// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The recognition hook (SPEC 4.1): any object recogniser becomes an interest filter,
// interest being the score of the detections covering a pixel. Shipped recogniser:
// FeatureRecognizer, a planar-ish object from reference photos by ORB keypoints (Rublee et
// al. 2011), Lowe's ratio test and a RANSAC homography.
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <string>
#include <vector>

#include "unseen/select/interest_filter.h"

namespace unseen {

// One object found in an image.
struct Detection {
  std::vector<cv::Point2f> polygon;  // its outline, image px (a box: its 4 corners)
  double score = 0.0;                // confidence in [0, 1]
};

class ObjectRecognizer {
 public:
  virtual ~ObjectRecognizer() = default;
  virtual std::string name() const = 0;
  // The objects in `bgr8` (CV_8UC3), none when there are none.
  virtual std::vector<Detection> Detect(const cv::Mat& bgr8) = 0;
};

// Interest = the highest score of the detections whose polygon holds the pixel, 0 outside
// every detection. The recogniser is not run when no pixel has interest left.
class RecognitionFilter : public InterestFilter {
 public:
  explicit RecognitionFilter(std::unique_ptr<ObjectRecognizer> recognizer);
  std::string name() const override { return "recognition"; }
  void Apply(const FilterFrame& frame, cv::Mat* interest) override;
  const ObjectRecognizer& recognizer() const { return *recognizer_; }

 private:
  std::unique_ptr<ObjectRecognizer> recognizer_;
};

// ---- ORB + homography ----------------------------------------------------------------

struct FeatureRecognizerOptions {
  int reference_features = 1000;     // ORB keypoints kept per reference photo
  int frame_features = 1500;         // ORB keypoints kept per frame
  double ratio = 0.75;               // Lowe's ratio test: best / second-best Hamming distance
  double ransac_threshold_px = 4.0;  // reprojection error of a homography inlier
  int min_inliers = 12;              // fewer: not the object
  double min_inlier_ratio = 0.25;    // inliers / matches passing the ratio test, at least
  // Score = min(1, inliers / full_score_inliers).
  int full_score_inliers = 50;
  // The projected outline must be convex with sides of at least min_side_px, cover at
  // least min_area_px2 and at most max_area_fraction of the image, and have between
  // 1/max_area_change and max_area_change times the reference outline's area.
  double min_side_px = 8.0;
  double min_area_px2 = 400.0;
  double max_area_fraction = 0.95;
  double max_area_change = 25.0;
  void Check() const;
};

// Recognises an object from one or more reference photos (its region in each, a face or
// the whole object seen from one side). Detect() returns the best detection per reference
// photo that passes the checks above: the photo's outline (rectangle corners) mapped by
// the homography.
class FeatureRecognizer : public ObjectRecognizer {
 public:
  explicit FeatureRecognizer(const FeatureRecognizerOptions& options);
  std::string name() const override { return "feature"; }

  // Adds a reference: `image` (any type ToFloatBgr reads) and the object's rectangle in
  // it, px (empty: the whole image). Throws unseen::Error naming `what` when the rectangle
  // is outside the image or holds too few keypoints to ever reach min_inliers.
  void AddReference(const cv::Mat& image, cv::Rect rect, const std::string& what = "reference");
  int num_references() const { return static_cast<int>(references_.size()); }

  std::vector<Detection> Detect(const cv::Mat& bgr8) override;

 private:
  struct Reference {
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    std::vector<cv::Point2f> outline;
    double area_px2 = 0.0;
  };

  FeatureRecognizerOptions options_;
  cv::Ptr<cv::ORB> reference_orb_, frame_orb_;
  cv::BFMatcher matcher_{cv::NORM_HAMMING};
  std::vector<Reference> references_;
};

}  // namespace unseen
