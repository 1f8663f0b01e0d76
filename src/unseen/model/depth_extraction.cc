// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/depth_extraction.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "unseen/image/image_io.h"
#include "unseen/model/plane_sweep.h"
#include "unseen/model/stereo_depth.h"
#include "unseen/util/error.h"

namespace unseen {


int DepthMap::ValidPixels() const { return depth.empty() ? 0 : cv::countNonZero(depth > 0.0f); }

cv::Mat Texturedness(const cv::Mat& image, const PixelRect& roi) {
  const PixelRect whole{0, 0, image.cols, image.rows};
  const PixelRect r = roi.empty() ? whole : roi.Intersect(whole);
  cv::Mat out = cv::Mat::zeros(image.size(), CV_32FC1);
  if (r.empty()) return out;
  // The region grown by the differences' reach, so that its own pixels are as over the
  // whole image.
  const PixelRect g = r.Grow(1).Intersect(whole);
  const cv::Mat part = image(ToCvRect(g));
  const cv::Mat bgr = part.type() == CV_32FC3 ? part : ToFloatBgr(part, "texturedness input");
  cv::Mat gx, gy;
  // Central differences (I(x+1) - I(x-1)) / 2 per channel.
  cv::Sobel(bgr, gx, CV_32F, 1, 0, 1, 0.5, 0.0, cv::BORDER_REPLICATE | cv::BORDER_ISOLATED);
  cv::Sobel(bgr, gy, CV_32F, 0, 1, 1, 0.5, 0.0, cv::BORDER_REPLICATE | cv::BORDER_ISOLATED);
  const cv::Mat sq = gx.mul(gx) + gy.mul(gy);
  cv::Mat t;
  cv::transform(sq, t, cv::Matx13f(1.0f, 1.0f, 1.0f));
  const cv::Rect inner(r.x0 - g.x0, r.y0 - g.y0, r.width(), r.height());
  t(inner).copyTo(out(ToCvRect(r)));
  return out;
}

cv::Mat GreyImage(const Frame& frame, const Rig& rig, int camera, const std::string& source) {
  const RigCamera& cam = rig.cameras[camera];
  UNSEEN_CHECK(static_cast<int>(frame.images.size()) == rig.size() && !frame.images[camera].empty(),
               "depth source {}: no image of camera '{}' in frame {}", source, cam.name,
               frame.frame_id);
  const cv::Mat& im = frame.images[camera];
  UNSEEN_CHECK(im.cols == cam.intrinsics.width && im.rows == cam.intrinsics.height,
               "depth source {}: image of camera '{}' is {}x{}, the camera is {}x{}", source,
               cam.name, im.cols, im.rows, cam.intrinsics.width, cam.intrinsics.height);
  const cv::Mat bgr =
      im.type() == CV_32FC3 ? im : ToFloatBgr(im, "camera '" + cam.name + "' image");
  cv::Mat grey;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  return grey;
}

namespace {

// The frame's depth image of the reference camera, cut to the range and the region.
class SensorDepth : public DepthSource {
 public:
  SensorDepth(const Rig& rig, int reference, const DepthExtractionOptions& options)
      : rig_(rig), reference_(reference), options_(options) {}

  DepthMap Extract(const Frame& frame, const PixelRect& roi, double near_m,
                   double far_m) const override {
    const RigCamera& cam = rig_.cameras[reference_];
    UNSEEN_CHECK(
        static_cast<int>(frame.images.size()) == rig_.size() && !frame.images[reference_].empty(),
        "depth source sensor: no colour image of camera '{}' in frame {}", cam.name,
        frame.frame_id);
    UNSEEN_CHECK(
        static_cast<int>(frame.depths.size()) == rig_.size() && !frame.depths[reference_].empty(),
        "depth source sensor: frame {} has no depth image of camera '{}' (the "
        "sequence has no depth; use --depth planesweep or stereo)",
        frame.frame_id, cam.name);
    const cv::Mat& d = frame.depths[reference_];
    UNSEEN_CHECK(
        d.type() == CV_32FC1 && d.cols == cam.intrinsics.width && d.rows == cam.intrinsics.height,
        "depth source sensor: depth of camera '{}' is {}x{} type {}; expected {}x{} "
        "CV_32FC1 metres",
        cam.name, d.cols, d.rows, d.type(), cam.intrinsics.width, cam.intrinsics.height);
    const double near = near_m > 0.0 ? near_m : options_.min_depth_m;
    const double far = far_m > 0.0 ? far_m : options_.max_depth_m;
    DepthMap out;
    out.depth = cv::Mat::zeros(d.size(), CV_32FC1);
    out.dense = true;
    const PixelRect r =
        (roi.empty() ? cam.intrinsics.ImageRect() : roi).Intersect(cam.intrinsics.ImageRect());
    out.texturedness = Texturedness(frame.images[reference_], r);
    for (int y = r.y0; y < r.y1; ++y) {
      const float* in = d.ptr<float>(y);
      float* o = out.depth.ptr<float>(y);
      for (int x = r.x0; x < r.x1; ++x) {
        if (in[x] >= near && in[x] <= far) o[x] = in[x];
      }
    }
    return out;
  }
  DepthSourceKind kind() const override { return DepthSourceKind::kSensor; }

 private:
  Rig rig_;
  int reference_;
  DepthExtractionOptions options_;
};

}  // namespace

DepthSourceKind NaturalDepthSource(const Rig& rig, int reference, bool has_depth) {
  if (has_depth || rig.size() < 2) return DepthSourceKind::kSensor;
  if (rig.size() > 2) return DepthSourceKind::kPlaneSweep;
  const RigCamera& ref = rig.cameras[reference];
  const RigCamera& other = rig.cameras[reference == 0 ? 1 : 0];
  // The baseline in the reference camera's frame: the matcher wants it across the rows.
  const Eigen::Vector3d baseline = ref.cam_from_world() * other.world_from_cam.translation();
  // The angle between the optical axes (a pair toed in towards the object).
  const Eigen::Vector3d ref_axis = ref.world_from_cam.rotation() * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d other_axis = other.world_from_cam.rotation() * Eigen::Vector3d::UnitZ();
  const double convergence_deg =
      std::acos(std::clamp(ref_axis.dot(other_axis), -1.0, 1.0)) * 180.0 / M_PI;
  return std::abs(baseline.x()) >= std::abs(baseline.y()) &&
                 convergence_deg <= kMaxStereoConvergenceDeg
             ? DepthSourceKind::kStereo
             : DepthSourceKind::kPlaneSweep;
}

std::unique_ptr<DepthSource> MakeDepthSource(const Rig& rig, int reference,
                                             const DepthExtractionOptions& options) {
  options.Check();
  UNSEEN_CHECK(reference >= 0 && reference < rig.size(),
               "depth source: reference camera {} not in a rig of {} cameras", reference,
               rig.size());
  switch (options.source) {
    case DepthSourceKind::kSensor:
      return std::make_unique<SensorDepth>(rig, reference, options);
    case DepthSourceKind::kStereo:
      return std::make_unique<StereoDepth>(rig, reference, options);
    case DepthSourceKind::kPlaneSweep:
      return std::make_unique<PlaneSweepDepth>(rig, reference, options);
  }
  ThrowError("depth source: unknown kind {}", static_cast<int>(options.source));
}

}  // namespace unseen
