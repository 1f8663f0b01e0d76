// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/system/system_overlay.h"

#include <fmt/format.h>

#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "unseen/eval/overlay.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

const cv::Scalar kCandidateColour(0, 220, 255);  // BGR
const cv::Scalar kSelectedColour(255, 255, 0);
const cv::Scalar kTrackingColour(0, 255, 0);
const cv::Scalar kLostColour(0, 0, 255);

// Red tint where there is interest: image += alpha * S * (red - image).
void TintInterest(const cv::Mat& interest, double alpha, cv::Mat* image) {
  if (interest.empty() || interest.size() != image->size() || alpha <= 0.0) return;
  for (int y = 0; y < image->rows; ++y) {
    const float* s = interest.ptr<float>(y);
    cv::Vec3b* px = image->ptr<cv::Vec3b>(y);
    for (int x = 0; x < image->cols; ++x) {
      const float a = static_cast<float>(alpha) * std::clamp(s[x], 0.0f, 1.0f);
      if (a <= 0.0f) continue;
      px[x][0] = cv::saturate_cast<uchar>(px[x][0] * (1.0f - a));
      px[x][1] = cv::saturate_cast<uchar>(px[x][1] * (1.0f - a));
      px[x][2] = cv::saturate_cast<uchar>(px[x][2] * (1.0f - a) + 255.0f * a);
    }
  }
}

// The object's axes (x red, y green, z blue) from the bounding sphere's centre.
void DrawAxes(const Mesh& model, const PinholeCamera& camera, const Rigid3d& cam_from_obj,
              double length_share, int thickness, cv::Mat* image) {
  Eigen::Vector3f centre;
  float radius = 0.0f;
  model.BoundingSphere(&centre, &radius);
  const Eigen::Vector3d origin = cam_from_obj * centre.cast<double>();
  if (origin.z() <= 1e-3 || length_share <= 0.0) return;
  const Eigen::Vector2d o = camera.Project(origin);
  const cv::Scalar colours[3] = {{0, 0, 255}, {0, 255, 0}, {255, 0, 0}};
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Vector3d tip =
        cam_from_obj *
        (centre.cast<double>() + length_share * radius * Eigen::Vector3d::Unit(axis));
    if (tip.z() <= 1e-3) continue;
    const Eigen::Vector2d t = camera.Project(tip);
    cv::line(*image, cv::Point2d(o.x(), o.y()), cv::Point2d(t.x(), t.y()), colours[axis], thickness,
             cv::LINE_AA);
  }
}

}  // namespace

void SystemOverlayOptions::Check() const {
  UNSEEN_CHECK(interest_alpha >= 0.0 && interest_alpha <= 1.0,
               "system overlay: interest_alpha {} not in [0, 1]", interest_alpha);
  UNSEEN_CHECK(line_thickness_px >= 1, "system overlay: line_thickness_px {} must be >= 1",
               line_thickness_px);
  UNSEEN_CHECK(axis_share >= 0.0, "system overlay: axis_share {} must be >= 0", axis_share);
  UNSEEN_CHECK(font_scale > 0.0, "system overlay: font_scale {} must be > 0", font_scale);
}

void DrawSystemOverlay(const SystemStep& step, const Mesh* model, const PinholeCamera& camera,
                       const Rigid3d& cam_from_world, const SystemOverlayOptions& options,
                       cv::Mat* image) {
  options.Check();
  UNSEEN_CHECK(image != nullptr && !image->empty(), "system overlay: no image to draw on");
  if (image->type() == CV_32FC3) {
    image->convertTo(*image, CV_8UC3, 255.0);
  }
  UNSEEN_CHECK(image->type() == CV_8UC3, "system overlay: the image must be CV_8UC3 or CV_32FC3");
  TintInterest(step.interest, options.interest_alpha, image);
  for (const PixelRect& box : step.candidates) {
    cv::rectangle(*image, ToCvRect(box), kCandidateColour, 1);
  }
  if (!step.region.empty()) {
    cv::rectangle(*image, ToCvRect(step.region), kSelectedColour, options.line_thickness_px);
  }
  std::string line = fmt::format("frame {}  {}", step.frame_id, ToString(step.status));
  if (step.track) {
    const bool tracking = step.status == SystemStatus::kTracking;
    const cv::Scalar colour = tracking ? kTrackingColour : kLostColour;
    line += fmt::format("  conf {:.2f}", step.track->confidence);
    if (model != nullptr) {
      const Rigid3d cam_from_obj = cam_from_world * step.track->world_from_obj;
      cv::polylines(*image, SilhouetteOutline(*model, camera, cam_from_obj), true, colour,
                    options.line_thickness_px, cv::LINE_AA);
      DrawAxes(*model, camera, cam_from_obj, options.axis_share, options.line_thickness_px, image);
    }
  }
  const cv::Point at(8, static_cast<int>(8 + 22 * options.font_scale));
  cv::putText(*image, line, at, cv::FONT_HERSHEY_SIMPLEX, options.font_scale, cv::Scalar(0, 0, 0),
              3, cv::LINE_AA);
  cv::putText(*image, line, at, cv::FONT_HERSHEY_SIMPLEX, options.font_scale,
              cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
}

}  // namespace unseen
