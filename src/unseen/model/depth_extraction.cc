// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/depth_extraction.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "unseen/image/image_io.h"
#include "unseen/model/plane_sweep.h"
#include "unseen/model/stereo_depth.h"
#include "unseen/util/error.h"

namespace unseen {

std::string ToString(DepthSourceKind kind) {
  switch (kind) {
    case DepthSourceKind::kPlaneSweep:
      return "planesweep";
    case DepthSourceKind::kStereo:
      return "stereo";
    case DepthSourceKind::kSensor:
      return "sensor";
  }
  return "?";
}

DepthSourceKind ParseDepthSourceKind(const std::string& text) {
  for (DepthSourceKind k :
       {DepthSourceKind::kPlaneSweep, DepthSourceKind::kStereo, DepthSourceKind::kSensor}) {
    if (text == ToString(k)) return k;
  }
  ThrowError("depth source '{}' is not one of planesweep, stereo, sensor", text);
}

void PlaneSweepOptions::Check() const {
  UNSEEN_CHECK(planes >= 4 && planes <= 1024, "plane_sweep.planes {} must be in [4, 1024]", planes);
  UNSEEN_CHECK(window_px >= 3 && window_px % 2 == 1 && window_px <= 31,
               "plane_sweep.window_px {} must be odd and in [3, 31]", window_px);
  UNSEEN_CHECK(best_share > 0.0 && best_share <= 1.0, "plane_sweep.best_share {} must be in (0, 1]",
               best_share);
  UNSEEN_CHECK(max_cost > 0.0 && max_cost <= 2.0, "plane_sweep.max_cost {} must be in (0, 2]",
               max_cost);
  UNSEEN_CHECK(uniqueness >= 0.0 && uniqueness < 1.0, "plane_sweep.uniqueness {} must be in [0, 1)",
               uniqueness);
  UNSEEN_CHECK(min_support >= 0 && min_support <= 24,
               "plane_sweep.min_support {} must be in [0, 24]", min_support);
  UNSEEN_CHECK(refine_iterations >= 0 && refine_iterations <= 10,
               "plane_sweep.refine_iterations {} must be in [0, 10]", refine_iterations);
  UNSEEN_CHECK(smoothness >= 0.0 && std::isfinite(smoothness),
               "plane_sweep.smoothness {} must be >= 0", smoothness);
}

void StereoOptions::Check() const {
  UNSEEN_CHECK(num_disparities >= 16 && num_disparities % 16 == 0 && num_disparities <= 512,
               "stereo.num_disparities {} must be a multiple of 16 in [16, 512]", num_disparities);
  UNSEEN_CHECK(block_size >= 3 && block_size % 2 == 1 && block_size <= 21,
               "stereo.block_size {} must be odd and in [3, 21]", block_size);
  UNSEEN_CHECK(uniqueness_ratio >= 0 && uniqueness_ratio <= 100,
               "stereo.uniqueness_ratio {} must be in [0, 100]", uniqueness_ratio);
  UNSEEN_CHECK(speckle_window >= 0, "stereo.speckle_window {} must be >= 0", speckle_window);
  UNSEEN_CHECK(speckle_range >= 1, "stereo.speckle_range {} must be >= 1", speckle_range);
}

void DepthExtractionOptions::Check() const {
  UNSEEN_CHECK(min_depth_m > 0.0 && std::isfinite(min_depth_m), "depth.min_depth_m {} must be > 0",
               min_depth_m);
  UNSEEN_CHECK(max_depth_m > min_depth_m && std::isfinite(max_depth_m),
               "depth.max_depth_m {} must be > min_depth_m {}", max_depth_m, min_depth_m);
  UNSEEN_CHECK(min_texturedness >= 0.0 && std::isfinite(min_texturedness),
               "depth.min_texturedness {} must be >= 0", min_texturedness);
  plane_sweep.Check();
  stereo.Check();
}

int DepthMap::ValidPixels() const { return depth.empty() ? 0 : cv::countNonZero(depth > 0.0f); }

cv::Mat Texturedness(const cv::Mat& image) {
  const cv::Mat bgr = image.type() == CV_32FC3 ? image : ToFloatBgr(image, "texturedness input");
  cv::Mat gx, gy;
  // Central differences (I(x+1) - I(x-1)) / 2 per channel.
  cv::Sobel(bgr, gx, CV_32F, 1, 0, 1, 0.5, 0.0, cv::BORDER_REPLICATE);
  cv::Sobel(bgr, gy, CV_32F, 0, 1, 1, 0.5, 0.0, cv::BORDER_REPLICATE);
  cv::Mat sq = gx.mul(gx) + gy.mul(gy);
  cv::Mat out;
  cv::transform(sq, out, cv::Matx13f(1.0f, 1.0f, 1.0f));
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
    out.texturedness = Texturedness(frame.images[reference_]);
    out.depth = cv::Mat::zeros(d.size(), CV_32FC1);
    out.dense = true;
    const PixelRect r =
        (roi.empty() ? cam.intrinsics.ImageRect() : roi).Intersect(cam.intrinsics.ImageRect());
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
