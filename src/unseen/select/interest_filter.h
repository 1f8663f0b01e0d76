// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Interest filters (SPEC 4.1, thesis 2.2.1): each says, per pixel, how much of interest it
// finds there, in [0, 1]. They are chained: the first receives an interest map of ones,
// and each multiplies it by its own judgement (2.4), S_n = S_{n-1} * S_n,calc, so a filter
// only ever lowers interest and may skip the pixels already at zero. The bank and its
// configuration file are in interest_filter_bank.h; the filters shipped here:
//  * ColourFilter (2.5): closeness to one of a few reference colours;
//  * MotionFilter: moving pixels, by OpenCV's adaptive background model (MOG2);
//  * PositionFilter: pixels whose 3-D point (from the depth image) lies in a box;
//  * VelocityFilter: pixels moving along a given image direction (dense optical flow);
//  * TrackedMotionFilter: pixels moving as the tracked object does (for model rebuilds).
// In files of their own: CooccurrenceFilter (cooccurrence_filter.h), windows like a
// reference region by colour co-occurrence; RecognitionFilter (recognition_filter.h), the
// detections of an object recogniser.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/video/background_segm.hpp>
#include <opencv2/video/tracking.hpp>
#include <optional>
#include <string>
#include <vector>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"

namespace unseen {

// What a filter may look at: one camera's frame.
struct FilterFrame {
  cv::Mat image;           // CV_32FC3 BGR [0, 1]
  cv::Mat depth;           // CV_32FC1 metres (0 = none) registered to `image`, or empty
  PinholeCamera camera;    // of `image`
  Rigid3d world_from_cam;  // where the camera is
  double time_s = 0.0;
  // The tracked object, when there is one: its pose in this frame and in the previous one
  // (for the filters that follow it).
  std::optional<Rigid3d> world_from_obj, previous_world_from_obj;
};

class InterestFilter {
 public:
  virtual ~InterestFilter() = default;
  virtual std::string name() const = 0;
  // (2.4): multiplies `interest` (CV_32FC1 of the image's size, values in [0, 1]) by this
  // filter's interest, computed where `interest` is above zero. Throws unseen::Error
  // naming the filter for an image or depth map it cannot use.
  virtual void Apply(const FilterFrame& frame, cv::Mat* interest) = 0;
  // False while the filter cannot judge yet (a background model learning its first
  // frames); it then leaves no interest.
  virtual bool ready() const { return true; }
};

// ---- colour (2.5) --------------------------------------------------------------------

struct ColourFilterOptions {
  // Reference colours (BGR in [0, 1]) and, for each, the distance (in the same units) at
  // which interest falls to zero: S = clamp(sum_i clamp(1 - |I - I_i|^2 / r_i^2, 0, 1), 0, 1).
  std::vector<Eigen::Vector3f> colours_bgr;
  std::vector<float> radii;
  void Check() const;
};

class ColourFilter : public InterestFilter {
 public:
  explicit ColourFilter(const ColourFilterOptions& options);
  std::string name() const override { return "colour"; }
  void Apply(const FilterFrame& frame, cv::Mat* interest) override;

 private:
  ColourFilterOptions options_;
};

// ---- motion ----------------------------------------------------------------------------

struct MotionFilterOptions {
  int history = 100;            // frames the background model remembers
  double var_threshold = 16.0;  // squared Mahalanobis distance to call a pixel foreground
  bool detect_shadows = true;   // shadows (darker, same hue) are not motion
  double learning_rate = -1.0;  // per frame in [0, 1]; -1: 1 / frames seen, up to history
  int warmup_frames = 8;        // frames learnt before the filter judges (thesis: 5-10)
  int open_px = 3;              // morphological opening of the foreground (odd; 1 = none)
  void Check() const;
};

class MotionFilter : public InterestFilter {
 public:
  explicit MotionFilter(const MotionFilterOptions& options);
  std::string name() const override { return "motion"; }
  // Learns the frame into the background model; interest 1 on moving pixels, 0 elsewhere
  // (everywhere before warmup_frames frames).
  void Apply(const FilterFrame& frame, cv::Mat* interest) override;
  bool ready() const override { return frames_ >= options_.warmup_frames; }

 private:
  MotionFilterOptions options_;
  cv::Ptr<cv::BackgroundSubtractorMOG2> model_;
  int frames_ = 0;
  cv::Size size_;
};

// ---- position ------------------------------------------------------------------------

struct PositionFilterOptions {
  // An axis-aligned box in the world frame, metres: interest 1 where the pixel's 3-D
  // point lies inside, 0 elsewhere and where there is no depth.
  Eigen::Vector3d min_m = Eigen::Vector3d::Constant(-1.0);
  Eigen::Vector3d max_m = Eigen::Vector3d::Constant(1.0);
  void Check() const;
};

class PositionFilter : public InterestFilter {
 public:
  explicit PositionFilter(const PositionFilterOptions& options);
  std::string name() const override { return "position"; }
  // Throws unseen::Error when the frame has no depth map.
  void Apply(const FilterFrame& frame, cv::Mat* interest) override;

 private:
  PositionFilterOptions options_;
};

// ---- velocity ------------------------------------------------------------------------

struct VelocityFilterOptions {
  // Interest where the image moves along this direction (image axes, x right, y down; any
  // length) at least min_speed_px a frame: S = clamp((cos(angle) - cos(max_angle)) /
  // (1 - cos(max_angle)), 0, 1), the angle between the pixel's flow and the direction.
  Eigen::Vector2d direction = Eigen::Vector2d::UnitX();
  double min_speed_px = 0.5;
  double max_angle_deg = 45.0;
  void Check() const;
};

// Motion along a direction (SPEC 4.1's velocity IF: a conveyor's parts, a car coming from
// the left), from OpenCV's DIS dense optical flow between consecutive frames. Judges from
// its second frame on.
class VelocityFilter : public InterestFilter {
 public:
  explicit VelocityFilter(const VelocityFilterOptions& options);
  std::string name() const override { return "velocity"; }
  void Apply(const FilterFrame& frame, cv::Mat* interest) override;
  bool ready() const override { return ready_; }

 private:
  VelocityFilterOptions options_;
  cv::Ptr<cv::DISOpticalFlow> flow_;
  cv::Mat previous_;  // CV_8UC1 grey
  bool ready_ = false;
};

// ---- moving with the tracked object --------------------------------------------------

struct TrackedMotionFilterOptions {
  // A pixel moves with the object when its measured flow (to the previous frame) differs
  // from the flow the object's tracked motion predicts there by less than
  // max_difference_px + relative_difference * |predicted|; interest falls linearly from 1
  // (equal) to 0 at that distance.
  double max_difference_px = 1.0;
  double relative_difference = 0.3;
  // Below this predicted speed at the object's origin (px/frame) the object hardly moves
  // in the image and motion cannot tell it from what stands still: interest is left as is.
  double min_object_speed_px = 0.5;
  void Check() const;
};

// The velocity IF of SPEC 4.1 for model rebuilds: interest where the image moves under
// the same rigid motion as the tracked object (FilterFrame::world_from_obj and
// previous_world_from_obj). The predicted flow of a pixel takes its depth from the frame's
// depth map where measured, else the object origin's depth; the measured flow is OpenCV's
// DIS from this frame to the previous one. Without a tracked object (or before its second
// frame) it judges nothing and leaves interest as it is.
class TrackedMotionFilter : public InterestFilter {
 public:
  explicit TrackedMotionFilter(const TrackedMotionFilterOptions& options);
  std::string name() const override { return "tracked_motion"; }
  void Apply(const FilterFrame& frame, cv::Mat* interest) override;

 private:
  TrackedMotionFilterOptions options_;
  cv::Ptr<cv::DISOpticalFlow> flow_;
  cv::Mat previous_;  // CV_8UC1 grey
};

}  // namespace unseen
