// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Least-squares solve of the stacked 6-DoF optical-flow equations of all cameras
// (SPEC 3.1 step 5, 3.8) for the world-frame twist of the object about its origin, with
// iteratively re-weighted least squares on top (SPEC 3.9, robust estimation).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "unseen/geometry/rigid3.h"

namespace unseen {

enum class RobustKernel { kNone, kHuber, kTukey };
const char* ToString(RobustKernel kernel);  // "none", "huber", "tukey"
// Throws unseen::Error naming `what` for an unknown name.
RobustKernel ParseRobustKernel(const std::string& text, const std::string& what = "kernel");

struct FlowSolverOptions {
  RobustKernel kernel = RobustKernel::kHuber;  // on the normalized residual (pixels)
  // Kernel width in units of the robust residual scale (1.4826 MAD): Huber 1.345 and
  // Tukey 4.685 give 95 % efficiency on Gaussian noise.
  double kernel_width = 1.345;
  int irls_iterations = 2;       // re-weighted solves after the plain least-squares one
  double min_scale_px = 0.05;    // floor of the robust residual scale, pixels
  int min_equations = 24;        // fewer equations: no solution
  double damping = 1e-6;         // relative Levenberg damping of the normal equations
  void Check() const;
};

// The equations of one camera (one pyramid level): row i says a_i . (v_c, w_c) = b_i with
// (v_c, w_c) the twist in that camera's frame (FlowRowInCamera) and b_i = -It.
struct FlowEquations {
  Eigen::Matrix3d world_from_cam_rotation = Eigen::Matrix3d::Identity();  // R_wc
  std::vector<Eigen::Matrix<float, 6, 1>> rows;
  std::vector<float> rhs;            // b_i = -It (intensity)
  std::vector<float> inv_grad_norm;  // 1 / |grad Iv| (pixels per intensity): residual -> px
  void Clear() {
    rows.clear();
    rhs.clear();
    inv_grad_norm.clear();
  }
  int size() const { return static_cast<int>(rows.size()); }
  void Add(const float row[6], float b, float inv_grad) {
    rows.emplace_back(row[0], row[1], row[2], row[3], row[4], row[5]);
    rhs.push_back(b);
    inv_grad_norm.push_back(inv_grad);
  }
};

struct FlowSolution {
  bool ok = false;             // false: too few equations or a singular system
  Vector6d twist = Vector6d::Zero();  // (v [m], w [rad]), world frame, about the origin
  int equations = 0;
  double initial_rms_px = 0.0;  // RMS normal-flow residual |It| / |grad| before the update
  double final_rms_px = 0.0;    // RMS normalized residual of the linear model after it
  double robust_scale_px = 0.0; // last robust residual scale
  double min_eigenvalue = 0.0;  // smallest eigenvalue of the normal matrix (conditioning)
};

// Accumulates the 6x6 normal equations of all cameras (float rows, double sums), turns
// each camera's block into the world frame and solves by LDLT; then `irls_iterations`
// re-weighted solves. Cameras with no rows are skipped.
FlowSolution SolveFlow(const std::vector<FlowEquations>& cameras, const FlowSolverOptions& options);

}  // namespace unseen
