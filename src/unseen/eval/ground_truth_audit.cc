// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/eval/ground_truth_audit.h"

#include <cmath>
#include <cstdint>

#include <fmt/format.h>

#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"

namespace unseen {

void GroundTruthAuditOptions::Check() const {
  UNSEEN_CHECK(agree_distance_m > 0.0 && std::isfinite(agree_distance_m),
               "GroundTruthAuditOptions: agree_distance_m {} must be positive", agree_distance_m);
  UNSEEN_CHECK(min_agreement >= 0.0 && min_agreement <= 1.0,
               "GroundTruthAuditOptions: min_agreement {} must be in [0, 1]", min_agreement);
  UNSEEN_CHECK(min_pixels >= 1, "GroundTruthAuditOptions: min_pixels {} must be positive",
               min_pixels);
}

std::string GroundTruthAudit::Summary() const {
  double sum = 0.0;
  for (double a : agreement) sum += a >= 0.0 ? a : 0.0;
  return fmt::format(
      "ground truth vs measured depth: {} of {} frames judged, {} trusted (>= {:.0f} % of the "
      "model's pixels within {:.0f} mm), mean agreement {:.2f}",
      judged, frames.size(), trusted, 100.0 * options.min_agreement,
      1e3 * options.agree_distance_m, judged > 0 ? sum / judged : 0.0);
}

GroundTruthAudit AuditGroundTruthWithDepth(const Sequence& sequence, const Mesh& model,
                                           const GroundTruthAuditOptions& options) {
  options.Check();
  UNSEEN_CHECK(sequence.has_ground_truth(), "{}: no ground truth to audit", sequence.path());
  UNSEEN_CHECK(sequence.has_depth(), "{}: no depth images to audit the ground truth with",
               sequence.path());
  GroundTruthAudit audit;
  audit.options = options;
  const Rig& rig = sequence.rig();
  RenderOptions render_options;
  render_options.write_color = false;
  RenderBuffers buffers;
  for (int index = 0; index < sequence.num_frames(); ++index) {
    const std::optional<Rigid3d> world_from_obj = sequence.GroundTruth(index);
    if (!world_from_obj) continue;
    audit.frames.push_back(sequence.frame_id(index));
    audit.agreement.push_back(-1.0);
    const Frame frame = sequence.TryReadFrame(index);
    int64_t measured = 0, agreeing = 0;
    for (int c = 0; c < rig.size() && c < static_cast<int>(frame.depths.size()); ++c) {
      const cv::Mat& depth = frame.depths[c];
      if (depth.empty()) continue;
      const PinholeCamera& camera = rig.cameras[c].intrinsics;
      const Rigid3d cam_from_obj = rig.cameras[c].cam_from_world() * *world_from_obj;
      Render(model, camera, cam_from_obj, camera.ImageRect(), render_options, &buffers);
      if (buffers.roi.empty()) continue;
      for (int y = 0; y < buffers.depth.rows; ++y) {
        const float* rendered = buffers.depth.ptr<float>(y);
        const float* seen = depth.ptr<float>(y + buffers.roi.y0) + buffers.roi.x0;
        for (int x = 0; x < buffers.depth.cols; ++x) {
          if (!(rendered[x] > 0.0f) || !(seen[x] > 0.0f)) continue;
          ++measured;
          agreeing += std::abs(seen[x] - rendered[x]) < options.agree_distance_m;
        }
      }
    }
    if (measured < options.min_pixels) continue;
    const double share = double(agreeing) / double(measured);
    audit.agreement.back() = share;
    ++audit.judged;
    audit.trusted += share >= options.min_agreement;
  }
  return audit;
}

}  // namespace unseen
