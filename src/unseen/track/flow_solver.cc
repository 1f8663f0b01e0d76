// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/flow_solver.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "unseen/util/error.h"

namespace unseen {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

// Weighted normal equations of one camera, camera frame.
void Accumulate(const FlowEquations& eq, const std::vector<float>* weights, Matrix6d* h,
                Vector6d* g) {
  // Products and sums in float over blocks of equations (vectorised), the block sums in
  // double, so that the sum over thousands of equations keeps its precision.
  constexpr int kBlock = 64;
  double acc[27] = {0};
  const int n = eq.size();
  for (int begin = 0; begin < n; begin += kBlock) {
    const int end = std::min(n, begin + kBlock);
    float block[27] = {0};
    for (int i = begin; i < end; ++i) {
      const float* a = eq.rows[i].data();
      const float w = weights ? (*weights)[i] : 1.0f;
      if (w <= 0.0f) continue;
      const float wb = w * eq.rhs[i];
      float wa[6];
      for (int r = 0; r < 6; ++r) wa[r] = w * a[r];
      int k = 0;
      for (int r = 0; r < 6; ++r) {
        for (int c = r; c < 6; ++c) block[k++] += wa[r] * a[c];
      }
      for (int r = 0; r < 6; ++r) block[21 + r] += wb * a[r];
    }
    for (int k = 0; k < 27; ++k) acc[k] += block[k];
  }
  int k = 0;
  for (int r = 0; r < 6; ++r) {
    for (int c = r; c < 6; ++c, ++k) {
      (*h)(r, c) = acc[k];
      (*h)(c, r) = acc[k];
    }
    (*g)(r) = acc[21 + r];
  }
}

double Weight(RobustKernel kernel, double r, double width) {
  const double a = std::abs(r);
  switch (kernel) {
    case RobustKernel::kNone:
      return 1.0;
    case RobustKernel::kHuber:
      return a <= width ? 1.0 : width / a;
    case RobustKernel::kTukey: {
      if (a >= width) return 0.0;
      const double t = 1.0 - (r / width) * (r / width);
      return t * t;
    }
  }
  return 1.0;
}

}  // namespace

const char* ToString(RobustKernel kernel) {
  switch (kernel) {
    case RobustKernel::kNone: return "none";
    case RobustKernel::kHuber: return "huber";
    case RobustKernel::kTukey: return "tukey";
  }
  return "?";
}

RobustKernel ParseRobustKernel(const std::string& text, const std::string& what) {
  if (text == "none") return RobustKernel::kNone;
  if (text == "huber") return RobustKernel::kHuber;
  if (text == "tukey") return RobustKernel::kTukey;
  ThrowError("{}: unknown robust kernel '{}' (none, huber, tukey)", what, text);
}

void FlowSolverOptions::Check() const {
  UNSEEN_CHECK(kernel_width > 0.0 && std::isfinite(kernel_width),
               "solver.kernel_width {} must be > 0", kernel_width);
  UNSEEN_CHECK(irls_iterations >= 0 && irls_iterations <= 20,
               "solver.irls_iterations {} must be in [0, 20]", irls_iterations);
  UNSEEN_CHECK(min_scale_px > 0.0 && std::isfinite(min_scale_px),
               "solver.min_scale_px {} must be > 0", min_scale_px);
  UNSEEN_CHECK(min_equations >= 6, "solver.min_equations {} must be >= 6", min_equations);
  UNSEEN_CHECK(damping >= 0.0 && damping < 1.0, "solver.damping {} must be in [0, 1)", damping);
}

FlowSolution SolveFlow(const std::vector<FlowEquations>& cameras,
                       const FlowSolverOptions& options) {
  FlowSolution out;
  double sum_sq0 = 0.0;
  for (const FlowEquations& eq : cameras) {
    out.equations += eq.size();
    for (int i = 0; i < eq.size(); ++i) {
      const double r = eq.rhs[i] * eq.inv_grad_norm[i];
      sum_sq0 += r * r;
    }
  }
  if (out.equations == 0) return out;
  out.initial_rms_px = std::sqrt(sum_sq0 / out.equations);
  if (out.equations < options.min_equations) return out;

  std::vector<std::vector<float>> weights(cameras.size());
  std::vector<float> abs_residuals;
  Vector6d twist = Vector6d::Zero();
  const int solves = 1 + (options.kernel == RobustKernel::kNone ? 0 : options.irls_iterations);
  for (int pass = 0; pass < solves; ++pass) {
    Matrix6d h = Matrix6d::Zero();
    Vector6d g = Vector6d::Zero();
    for (size_t c = 0; c < cameras.size(); ++c) {
      const FlowEquations& eq = cameras[c];
      if (eq.size() == 0) continue;
      Matrix6d hc;
      Vector6d gc;
      Accumulate(eq, pass == 0 ? nullptr : &weights[c], &hc, &gc);
      // twist_c = B twist with B = blockdiag(R_cw, R_cw): H = B^T Hc B, g = B^T gc.
      Matrix6d b = Matrix6d::Zero();
      const Eigen::Matrix3d r_cw = eq.world_from_cam_rotation.transpose();
      b.topLeftCorner<3, 3>() = r_cw;
      b.bottomRightCorner<3, 3>() = r_cw;
      h.noalias() += b.transpose() * hc * b;
      g.noalias() += b.transpose() * gc;
    }
    const double trace = h.trace();
    if (!(trace > 0.0) || !std::isfinite(trace)) return out;
    Matrix6d damped = h;
    damped.diagonal().array() += options.damping * trace / 6.0;
    Eigen::LDLT<Matrix6d> ldlt(damped);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return out;
    const Vector6d x = ldlt.solve(g);
    if (!x.allFinite()) return out;
    twist = x;
    out.min_eigenvalue = Eigen::SelfAdjointEigenSolver<Matrix6d>(h, Eigen::EigenvaluesOnly)
                             .eigenvalues()(0);

    // Residuals of the linear model, normalized to pixels of normal flow.
    abs_residuals.resize(out.equations);
    float* abs_out = abs_residuals.data();
    double sum_sq = 0.0;
    for (size_t c = 0; c < cameras.size(); ++c) {
      const FlowEquations& eq = cameras[c];
      if (eq.size() == 0) continue;
      const Eigen::Matrix3d r_cw = eq.world_from_cam_rotation.transpose();
      Eigen::Matrix<float, 6, 1> tc;
      tc.head<3>() = (r_cw * twist.head<3>()).cast<float>();
      tc.tail<3>() = (r_cw * twist.tail<3>()).cast<float>();
      weights[c].resize(eq.size());
      float* res = weights[c].data();  // residuals for now, turned into weights below
      double camera_sum_sq = 0.0;     // a local, so that it stays in a register
      for (int i = 0; i < eq.size(); ++i) {
        const float r = (eq.rows[i].dot(tc) - eq.rhs[i]) * eq.inv_grad_norm[i];
        res[i] = r;
        *abs_out++ = std::abs(r);
        camera_sum_sq += double(r) * r;
      }
      sum_sq += camera_sum_sq;
    }
    out.final_rms_px = std::sqrt(sum_sq / out.equations);
    if (pass + 1 == solves) break;
    // The median of |r| from an even spread of at most kScaleSamples residuals: the scale
    // needs a few per cent accuracy, and the selection is the solve's costliest part.
    constexpr size_t kScaleSamples = 1024;
    const size_t stride = (abs_residuals.size() + kScaleSamples - 1) / kScaleSamples;
    size_t kept = 0;
    for (size_t i = 0; i < abs_residuals.size(); i += stride)
      abs_residuals[kept++] = abs_residuals[i];
    const size_t mid = kept / 2;
    std::nth_element(abs_residuals.begin(), abs_residuals.begin() + mid,
                     abs_residuals.begin() + kept);
    const double scale = std::max(1.4826 * abs_residuals[mid], options.min_scale_px);
    out.robust_scale_px = scale;
    const double width = options.kernel_width * scale;
    for (auto& w : weights) {
      for (float& v : w) v = static_cast<float>(Weight(options.kernel, v, width));
    }
  }
  out.ok = true;
  out.twist = twist;
  return out;
}

}  // namespace unseen
