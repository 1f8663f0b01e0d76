// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/render/silhouette_share.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"

namespace unseen {

double SilhouetteShareInImage(const Mesh& mesh, const PinholeCamera& camera,
                              const Rigid3d& cam_from_obj,
                              std::span<const Eigen::Vector3d, 8> box_corners_in_obj,
                              int max_side_px) {
  UNSEEN_CHECK(max_side_px >= 4, "SilhouetteShareInImage: max_side_px {} must be >= 4",
               max_side_px);
  // The box's projection, not clipped to the image.
  std::array<Eigen::Vector3d, 8> corners_in_cam;
  for (size_t i = 0; i < corners_in_cam.size(); ++i) {
    corners_in_cam[i] = cam_from_obj * box_corners_in_obj[i];
  }
  const std::optional<PinholeCamera::Bounds> bounds = camera.ProjectedBounds(corners_in_cam);
  if (!bounds) return 1.0;
  const double xl = bounds->x_min, xh = bounds->x_max, yl = bounds->y_min, yh = bounds->y_max;
  if (xl >= -0.5 && yl >= -0.5 && xh < camera.width - 0.5 && yh < camera.height - 0.5) {
    return 1.0;
  }
  // A camera whose image is the whole projection, `scale` original pixels a pixel: pixel u
  // of it has its centre at original x = (u + x0 + 0.5) * scale - 0.5.
  const double scale = std::max(1.0, std::max(xh - xl, yh - yl) / max_side_px);
  const int x0 = static_cast<int>(std::floor((xl + 0.5) / scale - 0.5));
  const int y0 = static_cast<int>(std::floor((yl + 0.5) / scale - 0.5));
  PinholeCamera whole = camera.Scaled(scale);
  whole.distortion.clear();
  whole.cx -= x0;
  whole.cy -= y0;
  whole.width = static_cast<int>(std::ceil((xh + 0.5) / scale - 0.5)) - x0 + 1;
  whole.height = static_cast<int>(std::ceil((yh + 0.5) / scale - 0.5)) - y0 + 1;
  RenderOptions options;
  options.write_color = false;
  RenderBuffers buffers;
  Render(mesh, whole, cam_from_obj, whole.ImageRect(), options, &buffers);
  long covered = 0, inside = 0;
  for (int v = 0; v < buffers.mask.rows; ++v) {
    const uint8_t* mask = buffers.mask.ptr<uint8_t>(v);
    const double y = (v + y0 + 0.5) * scale;  // original y + 0.5
    const bool row_inside = y >= 0.0 && y < camera.height;
    for (int u = 0; u < buffers.mask.cols; ++u) {
      if (!mask[u]) continue;
      ++covered;
      const double x = (u + x0 + 0.5) * scale;
      if (row_inside && x >= 0.0 && x < camera.width) ++inside;
    }
  }
  return covered > 0 ? double(inside) / double(covered) : 0.0;
}

}  // namespace unseen
