// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Least-squares solve of the stacked 6-DoF optical-flow equations of all cameras
// (SPEC 3.1 step 5, 3.8) for the world-frame twist of the object about its origin, with
// iteratively re-weighted least squares on top (SPEC 3.9, robust estimation).
#pragma once

#include <limits>
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

// How the residuals of one modality are judged and weighed against the others. The
// normalized residual of row i is r_i = (a_i . x - b_i) * inv_norm_i (pixels of normal flow
// for the photometric rows, metres for depth, ...); the robust kernel acts on r_i divided by
// its robust scale (1.4826 MAD, floored at min_scale). The whole modality is weighed by
// weight / noise^2, where noise is the robust scale of its residuals in the rows' own units
// (1.4826 MAD, floored at min_noise): each modality counts by its measured noise, and a
// modality alone gets the same solution whatever its weight.
struct ResidualModel {
  RobustKernel kernel = RobustKernel::kHuber;
  double kernel_width = 1.345;  // in robust scales
  double min_scale = 0.05;      // floor of the robust scale, normalized units
  double min_noise = 1e-4;      // floor of the noise, row units
  double weight = 1.0;          // multiplies 1 / noise^2
  // Ceiling of the noise, row units: where a row's noise is known, a measure from the
  // residuals would take a modality's disagreement with the others for noise and silence
  // it exactly when it disagrees.
  double max_noise = std::numeric_limits<double>::infinity();
  // Levenberg damping this modality adds to the normal equations, relative to the mean
  // diagonal of its own share of them (trace / 6): it steadies the directions it leaves
  // weakly determined without slowing the others' (which add their own, if any).
  double damping = 0.0;
  // 0: the rows count in every direction of the twist. > 0: the modality is subordinate, it
  // settles what the others leave open: along each generalized eigendirection of its normal
  // matrix against theirs (mu: its information there relative to theirs together) its rows
  // count with max(0, 1 - subordinate_ratio / mu), none where mu <= subordinate_ratio.
  // A demoted texture (a model's colours that drag the silhouette) still settles the spin
  // about an axis of symmetry but no longer pulls where the silhouette holds the pose.
  double subordinate_ratio = 0.0;
  void Check(const std::string& what) const;
};

// One modality's equations over all cameras of the rig (index = rig camera).
struct ModalityEquations {
  std::string name;  // "photometric", "depth", ... (reports)
  ResidualModel model;
  std::vector<FlowEquations> cameras;
  int size() const;
  void Clear();  // keeps the cameras and their capacity
  // RMS normalized residual at a zero twist over the `share` (in (0, 1]) of the equations
  // with the smallest residuals (share 1: ModalityStats::initial_rms); 0 without equations.
  double TrimmedRms(double share) const;
};

// What the solve saw of one modality.
struct ModalityStats {
  int equations = 0;
  double initial_rms = 0.0;   // RMS normalized residual before the update
  double final_rms = 0.0;     // RMS normalized residual of the linear model after it
  double robust_scale = 0.0;  // last robust scale, normalized units
  double noise = 0.0;         // last noise, row units (what weighed the modality)
};

struct FlowSolution {
  bool ok = false;             // false: too few equations or a singular system
  Vector6d twist = Vector6d::Zero();  // (v [m], w [rad]), world frame, about the origin
  int equations = 0;           // over all modalities
  // The first modality's (the photometric one's in the tracker): RMS normal-flow residual
  // |It| / |grad| before the update, RMS normalized residual after it, robust scale.
  double initial_rms_px = 0.0;
  double final_rms_px = 0.0;
  double robust_scale_px = 0.0;
  double min_eigenvalue = 0.0;  // smallest eigenvalue of the normal matrix (conditioning)
  // The (damped) normal matrix of the last solve, each modality's rows weighed by
  // weight / noise^2: the twist's information; zero when the solve failed.
  Matrix6d information = Matrix6d::Zero();
  std::vector<ModalityStats> modalities;  // in the order given
};

// Accumulates the 6x6 normal equations of all cameras (float rows, double sums), turns
// each camera's block into the world frame and solves by LDLT; then `irls_iterations`
// re-weighted solves. Cameras with no rows are skipped. The photometric rows alone, with
// the kernel of `options`.
FlowSolution SolveFlow(const std::vector<FlowEquations>& cameras, const FlowSolverOptions& options);

// 1.4826 times the median of `values` (a robust standard deviation), from an even spread of
// at most 1 024 of them; 0 for none. Reorders `values`.
double RobustSigma(std::vector<float>* values);

// One Gauss-Newton step over several modalities: each modality's normal equations, re-weighted
// by its own kernel and scale, weighed by weight / noise^2 (ResidualModel) and summed over
// modalities and cameras. `options` gives irls_iterations, min_equations (over all
// modalities) and damping; its kernel fields are not used. Null or empty modalities count as
// having no equations (their stats stay zero).
FlowSolution SolveJoint(const std::vector<const ModalityEquations*>& modalities,
                        const FlowSolverOptions& options);

// Whether successive Gauss-Newton updates swing about the optimum within the solve's noise:
// `update` turns back on `previous_update` (negative inner product under `information`, the
// normal matrix the update was solved with) and its squared length under that matrix,
// chi-square with 6 degrees of freedom for an update of noise alone, is below `max_chi2`.
// A zero previous update (the first round) never swings.
bool SwingsWithinNoise(const Vector6d& previous_update, const Vector6d& update,
                       const Matrix6d& information, double max_chi2);

}  // namespace unseen
