// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/stereo_depth.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "unseen/util/error.h"

namespace unseen {
namespace {

cv::Mat ToCv(const Eigen::Matrix3d& m) {
  cv::Mat out(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.at<double>(r, c) = m(r, c);
  }
  return out;
}

cv::Mat To8U(const cv::Mat& grey) {
  cv::Mat out;
  grey.convertTo(out, CV_8U, 255.0);
  return out;
}

}  // namespace

StereoDepth::StereoDepth(const Rig& rig, int reference, const DepthExtractionOptions& options)
    : rig_(rig), reference_(reference), options_(options) {
  options_.Check();
  UNSEEN_CHECK(rig_.size() >= 2, "depth source stereo needs two cameras; the rig has {}",
               rig_.size());
  const std::string& name = options_.stereo.other_camera;
  if (name.empty()) {
    other_ = reference_ == 0 ? 1 : 0;
  } else {
    other_ = rig_.Find(name);
    UNSEEN_CHECK(other_ >= 0, "depth source stereo: stereo.other_camera '{}' is not in the rig",
                 name);
    UNSEEN_CHECK(other_ != reference_,
                 "depth source stereo: stereo.other_camera '{}' is the reference camera", name);
  }
  const PinholeCamera& a = rig_.cameras[reference_].intrinsics;
  const PinholeCamera& b = rig_.cameras[other_].intrinsics;
  UNSEEN_CHECK(a.width == b.width && a.height == b.height,
               "depth source stereo: cameras '{}' ({}x{}) and '{}' ({}x{}) differ in size",
               rig_.cameras[reference_].name, a.width, a.height, rig_.cameras[other_].name, b.width,
               b.height);
  const double baseline = (rig_.cameras[other_].world_from_cam.translation() -
                           rig_.cameras[reference_].world_from_cam.translation())
                              .norm();
  UNSEEN_CHECK(baseline > 1e-4,
               "depth source stereo: cameras '{}' and '{}' share a centre "
               "(baseline {} m): no depth from their pair",
               rig_.cameras[reference_].name, rig_.cameras[other_].name, baseline);

  const RigCamera& ref = rig_.cameras[reference_];
  const RigCamera& other = rig_.cameras[other_];
  const Rigid3d other_from_ref = other.cam_from_world() * ref.world_from_cam;
  const cv::Mat k1 = ToCv(a.K()), k2 = ToCv(b.K());
  const cv::Mat rotation = ToCv(other_from_ref.RotationMatrix());
  const Eigen::Vector3d t = other_from_ref.translation();
  const cv::Mat translation = (cv::Mat_<double>(3, 1) << t.x(), t.y(), t.z());
  const cv::Size size(a.width, a.height);
  cv::Mat r1, r2, p1, p2, q;
  cv::stereoRectify(k1, cv::noArray(), k2, cv::noArray(), size, rotation, translation, r1, r2, p1,
                    p2, q, cv::CALIB_ZERO_DISPARITY, 0.0, size);
  const double tx = p2.at<double>(0, 3), ty = p2.at<double>(1, 3);
  UNSEEN_CHECK(std::abs(tx) >= std::abs(ty),
               "depth source stereo: cameras '{}' and '{}' are stacked vertically; the matcher "
               "needs a horizontal baseline",
               ref.name, other.name);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) rect_from_ref_(i, j) = r1.at<double>(i, j);
  }
  focal_px_ = p1.at<double>(0, 0);
  principal_x_ = p1.at<double>(0, 2);
  principal_y_ = p1.at<double>(1, 2);
  focal_baseline_ = std::abs(tx);
  mirrored_ = tx > 0.0;
  cv::initUndistortRectifyMap(k1, cv::noArray(), r1, p1, size, CV_32FC1, ref_map_x_, ref_map_y_);
  cv::initUndistortRectifyMap(k2, cv::noArray(), r2, p2, size, CV_32FC1, other_map_x_,
                              other_map_y_);
}

DepthMap StereoDepth::Extract(const Frame& frame, const PixelRect& roi, double near_m,
                              double far_m) const {
  const StereoOptions& o = options_.stereo;
  const RigCamera& ref = rig_.cameras[reference_];
  const PinholeCamera& kref = ref.intrinsics;
  const cv::Mat ref_grey = GreyImage(frame, rig_, reference_, "stereo");
  const cv::Mat other_grey = GreyImage(frame, rig_, other_, "stereo");
  DepthMap out;
  out.depth = cv::Mat::zeros(kref.height, kref.width, CV_32FC1);
  const PixelRect r = (roi.empty() ? kref.ImageRect() : roi).Intersect(kref.ImageRect());
  out.texturedness = Texturedness(frame.images[reference_], r);
  if (r.empty()) return out;
  const double near = near_m > 0.0 ? near_m : options_.min_depth_m;
  const double far = far_m > 0.0 ? far_m : options_.max_depth_m;

  const cv::Size size(kref.width, kref.height);
  const double fb = focal_baseline_;
  const bool mirrored = mirrored_;
  // The region's corners in the rectified reference image.
  const Eigen::Matrix3d& rect = rect_from_ref_;
  const Eigen::Matrix3d kref_inv = kref.K().inverse();
  auto rectified = [&](double u, double v, Eigen::Vector3d* ray) {
    *ray = rect * (kref_inv * Eigen::Vector3d(u, v, 1.0));
    return Eigen::Vector2d(focal_px_ * ray->x() / ray->z() + principal_x_,
                           focal_px_ * ray->y() / ray->z() + principal_y_);
  };
  double x_min = 1e9, x_max = -1e9, y_min = 1e9, y_max = -1e9;
  for (double u : {double(r.x0), double(r.x1 - 1)}) {
    for (double v : {double(r.y0), double(r.y1 - 1)}) {
      Eigen::Vector3d ray;
      const Eigen::Vector2d p = rectified(u, v, &ray);
      x_min = std::min(x_min, p.x());
      x_max = std::max(x_max, p.x());
      y_min = std::min(y_min, p.y());
      y_max = std::max(y_max, p.y());
    }
  }

  // Disparities of the depth range and, with search_behind, beyond it towards
  // max_depth_m, as many as num_disparities allows (the range's own first).
  const int band_min = std::max(0, static_cast<int>(std::floor(fb / far)));
  const int band_max = static_cast<int>(std::ceil(fb / near));
  int min_disparity = band_min;
  if (o.search_behind) {
    const int deepest = std::max(0, static_cast<int>(std::floor(fb / options_.max_depth_m)));
    min_disparity = std::min(band_min, std::max(deepest, band_max + 1 - o.num_disparities));
  }
  const int wanted = band_max - min_disparity + 1;
  const int num_disparities = std::clamp((wanted + 15) / 16 * 16, 16, o.num_disparities);
  const int max_disparity = min_disparity + num_disparities;

  // The rectified images over the region's rows and the columns its matches can reach (the
  // matcher's cost grows with the width it is given), with the matcher's margin.
  const int margin = o.block_size + 2;
  const int row0 = std::clamp(static_cast<int>(std::floor(y_min)) - margin, 0, size.height - 1);
  const int row1 =
      std::clamp(static_cast<int>(std::ceil(y_max)) + margin + 1, row0 + 1, size.height);
  // The reference's pixel x matches the other's at x - d (the other to the right, tx < 0)
  // or at x + d (mirrored).
  const int reach_left = mirrored ? 0 : max_disparity;
  const int reach_right = mirrored ? max_disparity : 0;
  const int col0 =
      std::clamp(static_cast<int>(std::floor(x_min)) - reach_left - margin, 0, size.width - 1);
  const int col1 = std::clamp(static_cast<int>(std::ceil(x_max)) + reach_right + margin + 1,
                              col0 + 1, size.width);

  cv::Mat ref_rect, other_rect;
  const cv::Rect window(col0, row0, col1 - col0, row1 - row0);
  cv::remap(To8U(ref_grey), ref_rect, ref_map_x_(window), ref_map_y_(window), cv::INTER_LINEAR);
  cv::remap(To8U(other_grey), other_rect, other_map_x_(window), other_map_y_(window),
            cv::INTER_LINEAR);
  if (mirrored) {
    cv::flip(ref_rect, ref_rect, 1);
    cv::flip(other_rect, other_rect, 1);
  }
  // The matcher leaves its first min_disparity + num_disparities columns unmatched: where the
  // image ends closer to the region than that, the pair is padded so that the region's own
  // columns are matched (a match off the other image then fails the uniqueness test).
  const int room = mirrored ? col1 - 1 - static_cast<int>(std::ceil(x_max))
                            : static_cast<int>(std::floor(x_min)) - col0;
  const int pad = std::max(0, max_disparity + margin - room);
  if (pad > 0) {
    cv::copyMakeBorder(ref_rect, ref_rect, 0, 0, pad, 0, cv::BORDER_REPLICATE);
    cv::copyMakeBorder(other_rect, other_rect, 0, 0, pad, 0, cv::BORDER_REPLICATE);
  }
  const int cn = 1;
  cv::Ptr<cv::StereoSGBM> sgbm = cv::StereoSGBM::create(
      min_disparity, num_disparities, o.block_size, 8 * cn * o.block_size * o.block_size,
      32 * cn * o.block_size * o.block_size, 1, 63, o.uniqueness_ratio, o.speckle_window,
      o.speckle_range, cv::StereoSGBM::MODE_SGBM);
  cv::Mat disparity16;
  sgbm->compute(ref_rect, other_rect, disparity16);
  disparity16 = disparity16.colRange(pad, disparity16.cols);
  if (mirrored) cv::flip(disparity16, disparity16, 1);

  // Each reference pixel's rectified position, its disparity there, its point back in the
  // reference camera.
  ForEachTexturedPixel(&out, r, options_.min_texturedness, [&](int x, int y, float* depth) {
    Eigen::Vector3d ray;
    const Eigen::Vector2d p = rectified(x, y, &ray);
    const int px = static_cast<int>(std::lround(p.x())) - col0;
    const int py = static_cast<int>(std::lround(p.y())) - row0;
    if (px < 0 || px >= disparity16.cols || py < 0 || py >= disparity16.rows) return;
    const int d16 = disparity16.at<int16_t>(py, px);
    if (d16 <= min_disparity * 16) return;  // unmatched (min - 1) or at infinity
    const double z_rect = fb / (d16 / 16.0);
    const Eigen::Vector3d in_rect = ray / ray.z() * z_rect;
    const double z = (rect.transpose() * in_rect).z();
    if (z >= near && z <= far) *depth = static_cast<float>(z);
  });
  return out;
}

}  // namespace unseen
