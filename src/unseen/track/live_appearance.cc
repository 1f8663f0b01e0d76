// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/live_appearance.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"

namespace unseen {

void LiveAppearanceOptions::Check() const {
  UNSEEN_CHECK(min_confidence >= 0.0 && min_confidence <= 1.0,
               "live_appearance.min_confidence {} must be in [0, 1]", min_confidence);
  UNSEEN_CHECK(first_overrun_share >= 0.0 && first_overrun_share <= 1.0,
               "live_appearance.first_overrun_share {} must be in [0, 1]", first_overrun_share);
  UNSEEN_CHECK(print_share >= 0.0 && std::isfinite(print_share),
               "live_appearance.print_share {} must be >= 0 (> 1: never)", print_share);
  UNSEEN_CHECK(print_min_gradient > 0.0 && print_min_gradient <= 1.0,
               "live_appearance.print_min_gradient {} must be in (0, 1]", print_min_gradient);
  UNSEEN_CHECK(print_inset_px >= 0 && print_inset_px <= 32,
               "live_appearance.print_inset_px {} must be in [0, 32]", print_inset_px);
  UNSEEN_CHECK(refresh_frames >= 1, "live_appearance.refresh_frames {} must be >= 1",
               refresh_frames);
  UNSEEN_CHECK(refresh_share_ratio >= 0.0 && refresh_share_ratio <= 1.0,
               "live_appearance.refresh_share_ratio {} must be in [0, 1]", refresh_share_ratio);
  UNSEEN_CHECK(margin_px >= 0 && margin_px <= 64, "live_appearance.margin_px {} must be in [0, 64]",
               margin_px);
  UNSEEN_CHECK(occlusion_tolerance > 0.0 && std::isfinite(occlusion_tolerance),
               "live_appearance.occlusion_tolerance {} must be > 0", occlusion_tolerance);
  UNSEEN_CHECK(photometric_weight > 0.0 && std::isfinite(photometric_weight),
               "live_appearance.photometric_weight {} must be > 0", photometric_weight);
  UNSEEN_CHECK(poor_fit_share >= 0.0 && poor_fit_share <= 1.0,
               "live_appearance.poor_fit_share {} must be in [0, 1]", poor_fit_share);
  UNSEEN_CHECK(poor_fit_frames >= 0, "live_appearance.poor_fit_frames {} must be >= 0",
               poor_fit_frames);
  UNSEEN_CHECK(poor_fit_best_share >= 0.0 && poor_fit_best_share <= 1.0,
               "live_appearance.poor_fit_best_share {} must be in [0, 1]", poor_fit_best_share);
  UNSEEN_CHECK(poor_fit_confidence >= 0.0 && poor_fit_confidence <= 1.0,
               "live_appearance.poor_fit_confidence {} must be in [0, 1]", poor_fit_confidence);
}

std::optional<Projector> CaptureProjector(const Mesh& model, const PinholeCamera& camera,
                                          const Rigid3d& cam_from_obj, const cv::Mat& image,
                                          const PixelRect& rect, float depth_tolerance_m) {
  UNSEEN_CHECK(image.type() == CV_32FC3 && image.cols == camera.width &&
                   image.rows == camera.height,
               "CaptureProjector: the image must be CV_32FC3 of the camera's {}x{} pixels",
               camera.width, camera.height);
  const PixelRect crop = rect.Intersect(camera.ImageRect());
  if (crop.empty()) return std::nullopt;
  RenderOptions options;
  options.write_color = false;
  RenderBuffers buffers;
  Render(model, camera, cam_from_obj, crop, options, &buffers);
  if (buffers.mask.empty() || cv::countNonZero(buffers.mask) == 0) return std::nullopt;
  Projector p;
  p.image = image(ToCvRect(crop)).clone();
  p.depth = buffers.depth;
  p.depth_tolerance_m = depth_tolerance_m;
  p.camera = camera;
  p.camera.width = crop.width();
  p.camera.height = crop.height();
  p.camera.cx -= crop.x0;
  p.camera.cy -= crop.y0;
  p.camera.distortion.clear();  // the frame's distortion was removed at input
  p.cam_from_obj = cam_from_obj;
  return p;
}

double TexturedShare(const Projector& p, double min_gradient, int inset_px) {
  if (p.image.empty() || p.depth.empty()) return -1.0;
  cv::Mat inside = p.depth > 0.0f;
  if (inset_px > 0) {
    cv::erode(
        inside, inside,
        cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * inset_px + 1, 2 * inset_px + 1)));
  }
  cv::Mat grey;
  cv::cvtColor(p.image, grey, cv::COLOR_BGR2GRAY);
  long object = 0, textured = 0;
  const float limit = static_cast<float>(4.0 * min_gradient * min_gradient);
  for (int y = 1; y + 1 < grey.rows; ++y) {
    const uint8_t* in = inside.ptr<uint8_t>(y);
    const float* g = grey.ptr<float>(y);
    const float* up = grey.ptr<float>(y - 1);
    const float* down = grey.ptr<float>(y + 1);
    for (int x = 1; x + 1 < grey.cols; ++x) {
      if (!in[x]) continue;
      ++object;
      const float gx = g[x + 1] - g[x - 1], gy = down[x] - up[x];  // twice the gradient
      textured += gx * gx + gy * gy > limit;
    }
  }
  return object > 0 ? double(textured) / double(object) : -1.0;
}

}  // namespace unseen
