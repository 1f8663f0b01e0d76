// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/select/interest_filter.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "unseen/util/error.h"

namespace unseen {
namespace {

void CheckInputs(const std::string& filter, const FilterFrame& frame, const cv::Mat& interest) {
  UNSEEN_CHECK(frame.image.type() == CV_32FC3 && !frame.image.empty(),
               "{} filter: the image must be CV_32FC3 BGR in [0, 1] (type {})", filter,
               frame.image.type());
  UNSEEN_CHECK(interest.type() == CV_32FC1 && interest.size() == frame.image.size(),
               "{} filter: the interest map must be CV_32FC1 of the image's {}x{} pixels", filter,
               frame.image.cols, frame.image.rows);
}

// The frame's image in 8-bit grey levels (what DIS flow takes).
cv::Mat Grey8(const FilterFrame& frame) {
  cv::Mat grey_float, grey;
  cv::cvtColor(frame.image, grey_float, cv::COLOR_BGR2GRAY);
  grey_float.convertTo(grey, CV_8U, 255.0);
  return grey;
}

cv::Ptr<cv::DISOpticalFlow> FastDis() {
  return cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_FAST);
}

}  // namespace

void ColourFilterOptions::Check() const {
  UNSEEN_CHECK(!colours_bgr.empty(), "colour filter: no reference colour");
  UNSEEN_CHECK(radii.size() == colours_bgr.size(),
               "colour filter: {} radii for {} colours; give one radius per colour", radii.size(),
               colours_bgr.size());
  for (size_t i = 0; i < colours_bgr.size(); ++i) {
    UNSEEN_CHECK(colours_bgr[i].allFinite() && colours_bgr[i].minCoeff() >= 0.0f &&
                     colours_bgr[i].maxCoeff() <= 1.0f,
                 "colour filter: colour {} has components outside [0, 1]", i);
    UNSEEN_CHECK(radii[i] > 0.0f && std::isfinite(radii[i]),
                 "colour filter: radius {} of colour {} must be > 0", radii[i], i);
  }
}

ColourFilter::ColourFilter(const ColourFilterOptions& options) : options_(options) {
  options_.Check();
}

void ColourFilter::Apply(const FilterFrame& frame, cv::Mat* interest) {
  CheckInputs(name(), frame, *interest);
  std::vector<float> inv_r2(options_.radii.size());
  for (size_t i = 0; i < inv_r2.size(); ++i)
    inv_r2[i] = 1.0f / (options_.radii[i] * options_.radii[i]);
  for (int y = 0; y < frame.image.rows; ++y) {
    const cv::Vec3f* px = frame.image.ptr<cv::Vec3f>(y);
    float* s = interest->ptr<float>(y);
    for (int x = 0; x < frame.image.cols; ++x) {
      if (!(s[x] > 0.0f)) continue;
      float calc = 0.0f;
      for (size_t i = 0; i < inv_r2.size(); ++i) {
        const Eigen::Vector3f& c = options_.colours_bgr[i];
        const float d2 = (px[x][0] - c[0]) * (px[x][0] - c[0]) +
                         (px[x][1] - c[1]) * (px[x][1] - c[1]) +
                         (px[x][2] - c[2]) * (px[x][2] - c[2]);
        calc += std::clamp(1.0f - d2 * inv_r2[i], 0.0f, 1.0f);
      }
      s[x] *= std::min(calc, 1.0f);
    }
  }
}

void MotionFilterOptions::Check() const {
  UNSEEN_CHECK(history >= 1, "motion filter: history {} must be >= 1", history);
  UNSEEN_CHECK(var_threshold > 0.0 && std::isfinite(var_threshold),
               "motion filter: var_threshold {} must be > 0", var_threshold);
  UNSEEN_CHECK(learning_rate == -1.0 || (learning_rate >= 0.0 && learning_rate <= 1.0),
               "motion filter: learning_rate {} must be in [0, 1] or -1 (automatic)",
               learning_rate);
  UNSEEN_CHECK(warmup_frames >= 1, "motion filter: warmup_frames {} must be >= 1", warmup_frames);
  UNSEEN_CHECK(open_px >= 1 && open_px % 2 == 1 && open_px <= 31,
               "motion filter: open_px {} must be odd, in [1, 31]", open_px);
}

MotionFilter::MotionFilter(const MotionFilterOptions& options) : options_(options) {
  options_.Check();
  model_ = cv::createBackgroundSubtractorMOG2(options_.history, options_.var_threshold,
                                              options_.detect_shadows);
}

void MotionFilter::Apply(const FilterFrame& frame, cv::Mat* interest) {
  CheckInputs(name(), frame, *interest);
  UNSEEN_CHECK(size_.empty() || size_ == frame.image.size(),
               "motion filter: the image is {}x{}; the background model was learnt at {}x{}",
               frame.image.cols, frame.image.rows, size_.width, size_.height);
  size_ = frame.image.size();
  cv::Mat image8, foreground;
  frame.image.convertTo(image8, CV_8UC3, 255.0);
  model_->apply(image8, foreground, options_.learning_rate);
  ++frames_;
  if (!ready()) {
    interest->setTo(0.0f);
    return;
  }
  // 255 moving, 127 shadow (not motion), 0 background.
  cv::Mat moving = foreground == 255;
  if (options_.open_px > 1) {
    cv::morphologyEx(
        moving, moving, cv::MORPH_OPEN,
        cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(options_.open_px, options_.open_px)));
  }
  interest->setTo(0.0f, moving == 0);
}

void PositionFilterOptions::Check() const {
  UNSEEN_CHECK(min_m.allFinite() && max_m.allFinite() && (min_m.array() < max_m.array()).all(),
               "position filter: the box [{}, {}, {}] - [{}, {}, {}] m is empty", min_m.x(),
               min_m.y(), min_m.z(), max_m.x(), max_m.y(), max_m.z());
}

PositionFilter::PositionFilter(const PositionFilterOptions& options) : options_(options) {
  options_.Check();
}

void PositionFilter::Apply(const FilterFrame& frame, cv::Mat* interest) {
  CheckInputs(name(), frame, *interest);
  UNSEEN_CHECK(frame.depth.type() == CV_32FC1 && frame.depth.size() == frame.image.size(),
               "position filter: needs a CV_32FC1 depth map of the image's size (the "
               "sequence has no depth images?)");
  const Eigen::Matrix3f rotation = frame.world_from_cam.RotationMatrix().cast<float>();
  const Eigen::Vector3f translation = frame.world_from_cam.translation().cast<float>();
  const Eigen::Vector3f lo = options_.min_m.cast<float>(), hi = options_.max_m.cast<float>();
  const float ifx = 1.0f / static_cast<float>(frame.camera.fx);
  const float ify = 1.0f / static_cast<float>(frame.camera.fy);
  const float cx = static_cast<float>(frame.camera.cx), cy = static_cast<float>(frame.camera.cy);
  for (int y = 0; y < frame.depth.rows; ++y) {
    const float* d = frame.depth.ptr<float>(y);
    float* s = interest->ptr<float>(y);
    for (int x = 0; x < frame.depth.cols; ++x) {
      if (!(s[x] > 0.0f)) continue;
      if (!(d[x] > 0.0f)) {
        s[x] = 0.0f;
        continue;
      }
      const Eigen::Vector3f p =
          rotation * Eigen::Vector3f((x - cx) * ifx * d[x], (y - cy) * ify * d[x], d[x]) +
          translation;
      if ((p.array() < lo.array()).any() || (p.array() > hi.array()).any()) s[x] = 0.0f;
    }
  }
}

void VelocityFilterOptions::Check() const {
  UNSEEN_CHECK(direction.allFinite() && direction.norm() > 1e-9,
               "velocity filter: direction [{}, {}] has no length", direction.x(), direction.y());
  UNSEEN_CHECK(std::isfinite(min_speed_px) && min_speed_px >= 0.0,
               "velocity filter: min_speed_px {} must be >= 0", min_speed_px);
  UNSEEN_CHECK(max_angle_deg > 0.0 && max_angle_deg <= 180.0,
               "velocity filter: max_angle_deg {} not in (0, 180]", max_angle_deg);
}

VelocityFilter::VelocityFilter(const VelocityFilterOptions& options)
    : options_((options.Check(), options)), flow_(FastDis()) {}

void VelocityFilter::Apply(const FilterFrame& frame, cv::Mat* interest) {
  CheckInputs(name(), frame, *interest);
  const cv::Mat grey = Grey8(frame);
  UNSEEN_CHECK(previous_.empty() || previous_.size() == grey.size(),
               "velocity filter: the image is {}x{}; the previous one was {}x{}", grey.cols,
               grey.rows, previous_.cols, previous_.rows);
  if (previous_.empty()) {
    previous_ = grey;
    interest->setTo(0.0f);
    return;
  }
  cv::Mat flow;
  flow_->calc(previous_, grey, flow);
  previous_ = grey;
  ready_ = true;
  const Eigen::Vector2f d = options_.direction.normalized().cast<float>();
  const float cos_max = static_cast<float>(std::cos(options_.max_angle_deg * M_PI / 180.0));
  const float min_speed = static_cast<float>(options_.min_speed_px);
  for (int y = 0; y < flow.rows; ++y) {
    const cv::Vec2f* f = flow.ptr<cv::Vec2f>(y);
    float* s = interest->ptr<float>(y);
    for (int x = 0; x < flow.cols; ++x) {
      if (s[x] <= 0.0f) continue;  // (2.4): a later filter skips what is of no interest
      const float speed = std::hypot(f[x][0], f[x][1]);
      if (speed < min_speed || speed <= 0.0f) {
        s[x] = 0.0f;
        continue;
      }
      const float cosine = (f[x][0] * d.x() + f[x][1] * d.y()) / speed;
      const float along = cos_max < 1.0f ? (cosine - cos_max) / (1.0f - cos_max) : 0.0f;
      s[x] *= std::clamp(along, 0.0f, 1.0f);
    }
  }
}

void TrackedMotionFilterOptions::Check() const {
  UNSEEN_CHECK(max_difference_px > 0.0, "tracked motion filter: max_difference_px {} must be > 0",
               max_difference_px);
  UNSEEN_CHECK(relative_difference >= 0.0,
               "tracked motion filter: relative_difference {} must be >= 0", relative_difference);
  UNSEEN_CHECK(min_object_speed_px >= 0.0,
               "tracked motion filter: min_object_speed_px {} must be >= 0", min_object_speed_px);
}

TrackedMotionFilter::TrackedMotionFilter(const TrackedMotionFilterOptions& options)
    : options_((options.Check(), options)), flow_(FastDis()) {}

void TrackedMotionFilter::Apply(const FilterFrame& frame, cv::Mat* interest) {
  CheckInputs(name(), frame, *interest);
  UNSEEN_CHECK(frame.depth.empty() ||
                   (frame.depth.type() == CV_32FC1 && frame.depth.size() == frame.image.size()),
               "tracked motion filter: the depth map must be CV_32FC1 of the image's size");
  const cv::Mat grey = Grey8(frame);
  const cv::Mat previous = previous_;
  previous_ = grey;
  if (previous.empty() || previous.size() != grey.size() || !frame.world_from_obj ||
      !frame.previous_world_from_obj) {
    return;  // nothing to compare with: no judgement
  }
  // Camera-frame points of this frame to the previous frame: the object's motion seen
  // from the camera, inverted.
  const Rigid3d cam_from_world = frame.world_from_cam.Inverse();
  const Rigid3d previous_from_current = cam_from_world * *frame.previous_world_from_obj *
                                        frame.world_from_obj->Inverse() * frame.world_from_cam;
  const Eigen::Matrix3f rotation = previous_from_current.RotationMatrix().cast<float>();
  const Eigen::Vector3f translation = previous_from_current.translation().cast<float>();
  const PinholeCamera& camera = frame.camera;
  const Eigen::Vector3d origin = cam_from_world * frame.world_from_obj->translation();
  if (origin.z() <= 1e-6) return;  // behind the camera
  const Eigen::Vector2d origin_px = camera.Project(origin);
  const Eigen::Vector2d origin_before = camera.Project(
      previous_from_current.RotationMatrix() * origin + previous_from_current.translation());
  if ((origin_before - origin_px).norm() < options_.min_object_speed_px) return;

  // Only where there is interest left (2.4), with a margin for the flow's support.
  cv::Mat any;
  cv::compare(*interest, 0.0f, any, cv::CMP_GT);
  const cv::Rect region =
      (cv::boundingRect(any) + cv::Size(32, 32) - cv::Point(16, 16)) & cv::Rect({}, grey.size());
  if (region.width < 8 || region.height < 8) return;
  cv::Mat flow;  // at this frame's pixels of `region`, towards the previous frame
  flow_->calc(grey(region).clone(), previous(region).clone(), flow);  // DIS: continuous only
  const float fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const float cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
  const float origin_depth = static_cast<float>(origin.z());
  const float base = static_cast<float>(options_.max_difference_px);
  const float relative = static_cast<float>(options_.relative_difference);
  for (int y = region.y; y < region.y + region.height; ++y) {
    const cv::Vec2f* f = flow.ptr<cv::Vec2f>(y - region.y) - region.x;
    const float* depth = frame.depth.empty() ? nullptr : frame.depth.ptr<float>(y);
    float* s = interest->ptr<float>(y);
    for (int x = region.x; x < region.x + region.width; ++x) {
      if (s[x] <= 0.0f) continue;  // (2.4)
      const float z = depth != nullptr && depth[x] > 0.0f ? depth[x] : origin_depth;
      const Eigen::Vector3f point(z * (x - cx) / fx, z * (y - cy) / fy, z);
      const Eigen::Vector3f before = rotation * point + translation;
      if (before.z() <= 1e-6f) {
        s[x] = 0.0f;
        continue;
      }
      const float px = fx * before.x() / before.z() + cx - x;
      const float py = fy * before.y() / before.z() + cy - y;
      const float tolerance = base + relative * std::hypot(px, py);
      const float difference = std::hypot(f[x][0] - px, f[x][1] - py);
      s[x] *= std::clamp(1.0f - difference / tolerance, 0.0f, 1.0f);
    }
  }
}

}  // namespace unseen
