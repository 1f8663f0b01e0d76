// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/surface_alignment.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <vector>

#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"

namespace unseen {


SurfaceAlignment AlignSurfaceToModel(const cv::Mat& depth, const cv::Mat& mask,
                                     const PinholeCamera& camera, const Mesh& model,
                                     const Rigid3d& cam_from_obj,
                                     const SurfaceAlignmentOptions& options) {
  options.Check();
  UNSEEN_CHECK(
      depth.type() == CV_32FC1 && depth.cols == camera.width && depth.rows == camera.height,
      "AlignSurfaceToModel: depth is {}x{} type {}; expected {}x{} CV_32FC1", depth.cols,
      depth.rows, depth.type(), camera.width, camera.height);
  SurfaceAlignment out;
  RenderOptions render_options;
  render_options.write_color = false;
  render_options.write_normals = true;
  RenderBuffers rendered;
  Render(model, camera, cam_from_obj, camera.ImageRect(), render_options, &rendered);
  if (rendered.depth.empty()) return out;

  // The measured points (camera frame), every second pixel.
  std::vector<Eigen::Vector3d> measured;
  for (int y = 0; y < depth.rows; y += 2) {
    for (int x = 0; x < depth.cols; x += 2) {
      const float z = depth.at<float>(y, x);
      if (!(z > 0.0f) || (!mask.empty() && !mask.at<uint8_t>(y, x))) continue;
      measured.push_back(camera.Unproject(Eigen::Vector2d(x, y), z));
    }
  }
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  Rigid3d correction;
  // One pass: pairs by projection of the corrected points into the render, residuals
  // along the model's normal; optionally the normal equations.
  auto pass = [&](Matrix6d* h, Vector6d* g, double* sum_sq) {
    int pairs = 0;
    for (const Eigen::Vector3d& m : measured) {
      const Eigen::Vector3d p = correction * m;
      const Eigen::Vector2d px = camera.Project(p);
      const int x = static_cast<int>(std::lround(px.x())),
                y = static_cast<int>(std::lround(px.y()));
      if (!(x >= 0 && y >= 0 && x < camera.width && y < camera.height)) continue;
      const float zq = rendered.depth.at<float>(y, x);
      if (!(zq > 0.0f)) continue;
      const cv::Vec3f nq = rendered.normal.at<cv::Vec3f>(y, x);
      const Eigen::Vector3d n(nq[0], nq[1], nq[2]);
      const Eigen::Vector3d q = camera.Unproject(Eigen::Vector2d(x, y), zq);
      const double r = n.dot(p - q);
      if (std::abs(r) > options.max_distance_m) continue;
      ++pairs;
      *sum_sq += r * r;
      if (!h) continue;
      const double w = std::abs(r) <= options.huber_m ? 1.0 : options.huber_m / std::abs(r);
      Vector6d j;
      j.head<3>() = n;           // translation
      j.tail<3>() = p.cross(n);  // rotation (small angle, about the camera's origin)
      *h += w * j * j.transpose();
      *g -= w * r * j;
    }
    return pairs;
  };
  double before = 0.0;
  const int pairs_before = pass(nullptr, nullptr, &before);
  if (pairs_before < options.min_points) return out;
  out.rms_before_m = std::sqrt(before / pairs_before);
  for (int it = 0; it < options.iterations; ++it) {
    Matrix6d h = Matrix6d::Zero();
    Vector6d g = Vector6d::Zero();
    double sum_sq = 0.0;
    if (pass(&h, &g, &sum_sq) < options.min_points) return out;
    h.diagonal().array() += options.damping * h.trace() / 6.0;
    const Eigen::LDLT<Matrix6d> ldlt(h);
    if (ldlt.info() != Eigen::Success) return out;
    const Vector6d step = ldlt.solve(g);
    if (!step.allFinite()) return out;
    Vector6d twist;
    twist.head<3>() = step.head<3>();
    twist.tail<3>() = step.tail<3>();
    correction = Rigid3d::Exp(twist) * correction;
    if (step.head<3>().norm() < 1e-5 && step.tail<3>().norm() < 1e-5) break;
  }
  double after = 0.0;
  out.pairs = pass(nullptr, nullptr, &after);
  if (out.pairs < options.min_points) return out;
  out.rms_after_m = std::sqrt(after / out.pairs);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& m : measured) centroid += m;
  centroid /= static_cast<double>(measured.size());
  out.shift_m = (correction * centroid - centroid).norm();
  const double angle_deg = Eigen::AngleAxisd(correction.rotation()).angle() * 180.0 / M_PI;
  if (out.shift_m > options.max_correction_m || angle_deg > options.max_correction_deg) {
    return out;
  }
  out.cam_correction = correction;
  out.ok = true;
  return out;
}

}  // namespace unseen
