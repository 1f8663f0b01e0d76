// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/flow_solver.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "unseen/util/error.h"

namespace unseen {
namespace {


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

void ResidualModel::Check(const std::string& what) const {
  UNSEEN_CHECK(kernel_width > 0.0 && std::isfinite(kernel_width),
               "{}.kernel_width {} must be > 0", what, kernel_width);
  UNSEEN_CHECK(min_scale > 0.0 && std::isfinite(min_scale), "{}.min_scale {} must be > 0", what,
               min_scale);
  UNSEEN_CHECK(min_noise > 0.0 && std::isfinite(min_noise), "{}.min_noise {} must be > 0", what,
               min_noise);
  UNSEEN_CHECK(damping >= 0.0 && damping < 1.0, "{}.damping {} must be in [0, 1)", what, damping);
  UNSEEN_CHECK(max_noise >= min_noise && !std::isnan(max_noise),
               "{}.max_noise {} must be >= min_noise {}", what, max_noise, min_noise);
  UNSEEN_CHECK(weight > 0.0 && std::isfinite(weight), "{}.weight {} must be > 0", what, weight);
  UNSEEN_CHECK(subordinate_ratio >= 0.0 && std::isfinite(subordinate_ratio),
               "{}.subordinate_ratio {} must be >= 0", what, subordinate_ratio);
}

int ModalityEquations::size() const {
  int n = 0;
  for (const FlowEquations& eq : cameras) n += eq.size();
  return n;
}

void ModalityEquations::Clear() {
  for (FlowEquations& eq : cameras) eq.Clear();
}

double ModalityEquations::TrimmedRms(double share) const {
  UNSEEN_CHECK(share > 0.0 && share <= 1.0, "TrimmedRms: share {} not in (0, 1]", share);
  std::vector<float> squared;
  squared.reserve(size());
  for (const FlowEquations& eq : cameras) {
    for (int i = 0; i < eq.size(); ++i) {
      const float r = eq.rhs[i] * eq.inv_grad_norm[i];
      squared.push_back(r * r);
    }
  }
  if (squared.empty()) return 0.0;
  const size_t kept = std::max<size_t>(1, static_cast<size_t>(share * squared.size()));
  if (kept < squared.size()) {
    std::nth_element(squared.begin(), squared.begin() + (kept - 1), squared.end());
  }
  double sum = 0.0;
  for (size_t i = 0; i < kept; ++i) sum += squared[i];
  return std::sqrt(sum / kept);
}

namespace {

// The k-th smallest (0-based) of n <= kMaxSelect non-negative floats, exactly what
// std::nth_element finds, about 4x faster: the bit patterns of non-negative floats order
// as the values do, so a radix select on them (11, 10, 10 bits) narrows the candidates to
// the bucket holding the k-th at each pass. The scale is taken several times per solve.
constexpr int kMaxSelect = 1024;
float SelectNonNegative(const float* values, int n, int k) {
  uint32_t a[kMaxSelect], b[kMaxSelect];
  std::memcpy(a, values, sizeof(float) * n);
  uint32_t* candidates = a;
  uint32_t* kept = b;
  constexpr int kShifts[3] = {20, 10, 0};
  constexpr uint32_t kMasks[3] = {2047, 1023, 1023};
  int histogram[2048];
  for (int pass = 0; pass < 3 && n > 1; ++pass) {
    const int shift = kShifts[pass];
    const uint32_t mask = kMasks[pass];
    std::fill(histogram, histogram + mask + 1, 0);
    for (int i = 0; i < n; ++i) ++histogram[(candidates[i] >> shift) & mask];
    uint32_t digit = 0;
    int below = 0;
    while (below + histogram[digit] <= k) below += histogram[digit++];
    int m = 0;
    for (int i = 0; i < n; ++i) {
      if (((candidates[i] >> shift) & mask) == digit) kept[m++] = candidates[i];
    }
    std::swap(candidates, kept);
    n = m;
    k -= below;
  }
  float out;
  std::memcpy(&out, &candidates[k], sizeof(float));
  return out;
}

}  // namespace

// 1.4826 times the median of the values (a robust standard deviation), from an even spread of
// at most 1 024 of them: the scale needs a few per cent accuracy, and the selection is the
// solve's costliest part. Reorders `values`.
double RobustSigma(std::vector<float>* values) {
  if (values->empty()) return 0.0;
  constexpr size_t kScaleSamples = kMaxSelect;
  const size_t stride = (values->size() + kScaleSamples - 1) / kScaleSamples;
  size_t kept = 0;
  bool negative = false;
  for (size_t i = 0; i < values->size(); i += stride) {
    negative |= std::signbit((*values)[i]);
    (*values)[kept++] = (*values)[i];
  }
  const size_t mid = kept / 2;
  if (negative) {  // not a spread of magnitudes: the general selection
    std::nth_element(values->begin(), values->begin() + mid, values->begin() + kept);
    return 1.4826 * (*values)[mid];
  }
  return 1.4826 * SelectNonNegative(values->data(), static_cast<int>(kept), static_cast<int>(mid));
}

namespace {

// The per-modality working state of the solve.
struct ModalityWork {
  const ModalityEquations* eq = nullptr;
  Matrix6d h = Matrix6d::Zero();  // this pass's share of the normal equations
  Vector6d g = Vector6d::Zero();
  std::vector<std::vector<float>> weights;  // per camera; residuals before they become weights
  std::vector<float> abs_normalized, abs_row;
  double noise = 0.0;
  ModalityStats stats;
};

// A subordinate modality's share (h, g) kept only where the leading modalities' normal
// matrix `lead` leaves the twist open (ResidualModel::subordinate_ratio): in the generalized
// eigenbasis X of (h, lead), X^T lead X = I and X^T h X = diag(mu), so h = lead X diag(mu)
// X^T lead and g = lead X (X^T g); each direction is scaled by max(0, 1 - ratio / mu).
// The generalized problem is invariant to the twist's units (radians against metres).
void KeepWhereOpen(const Matrix6d& lead, double ratio, Matrix6d* h, Vector6d* g) {
  // A ridge relative to each coordinate's own scale keeps `lead` positive definite where
  // the leading modalities see nothing at all (there the subordinate counts fully).
  Matrix6d b = lead;
  b.diagonal() += 1e-9 * (lead.diagonal() + h->diagonal()) +
                  Vector6d::Constant(1e-12 * (lead.trace() + h->trace()) / 6.0);
  Eigen::GeneralizedSelfAdjointEigenSolver<Matrix6d> solver(*h, b);
  if (solver.info() != Eigen::Success) return;  // kept whole
  const Matrix6d bx = b * solver.eigenvectors();
  const Vector6d mu = solver.eigenvalues().cwiseMax(0.0);
  Vector6d keep;
  for (int i = 0; i < 6; ++i) keep(i) = mu(i) > ratio ? 1.0 - ratio / mu(i) : 0.0;
  *g = bx * keep.cwiseProduct(solver.eigenvectors().transpose() * *g);
  *h = bx * keep.cwiseProduct(mu).asDiagonal() * bx.transpose();
}

}  // namespace

FlowSolution SolveJoint(const std::vector<const ModalityEquations*>& modalities,
                        const FlowSolverOptions& options) {
  FlowSolution out;
  std::vector<ModalityWork> work(modalities.size());
  bool robust = false;
  for (size_t m = 0; m < modalities.size(); ++m) {
    ModalityWork& mw = work[m];
    mw.eq = modalities[m];
    if (!mw.eq || mw.eq->size() == 0) continue;
    mw.stats.equations = mw.eq->size();
    out.equations += mw.stats.equations;
    robust |= mw.eq->model.kernel != RobustKernel::kNone;
    // Initial residuals: the right-hand sides (the residuals at a zero twist).
    double sum_sq = 0.0;
    mw.abs_row.clear();
    for (const FlowEquations& eq : mw.eq->cameras) {
      for (int i = 0; i < eq.size(); ++i) {
        const double r = eq.rhs[i] * eq.inv_grad_norm[i];
        sum_sq += r * r;
        mw.abs_row.push_back(std::abs(eq.rhs[i]));
      }
    }
    mw.stats.initial_rms = std::sqrt(sum_sq / mw.stats.equations);
    mw.noise = std::clamp(RobustSigma(&mw.abs_row), mw.eq->model.min_noise,
                          std::max(mw.eq->model.min_noise, mw.eq->model.max_noise));
    mw.weights.resize(mw.eq->cameras.size());
  }
  auto finish_stats = [&] {
    for (const ModalityWork& mw : work) out.modalities.push_back(mw.stats);
    if (!work.empty()) {
      out.initial_rms_px = work[0].stats.initial_rms;
      out.final_rms_px = work[0].stats.final_rms;
      out.robust_scale_px = work[0].stats.robust_scale;
    }
  };
  if (out.equations == 0 || out.equations < options.min_equations) {
    finish_stats();
    return out;
  }

  Vector6d twist = Vector6d::Zero();
  Matrix6d information = Matrix6d::Zero();  // the normal matrix `twist` was solved with
  const int solves = 1 + (robust ? options.irls_iterations : 0);
  for (int pass = 0; pass < solves; ++pass) {
    Matrix6d h = Matrix6d::Zero();
    Vector6d g = Vector6d::Zero();
    double modality_damping = 0.0;  // sum over modalities of damping * trace(H_m) / 6
    Matrix6d lead = Matrix6d::Zero();  // the modalities that are not subordinate
    for (ModalityWork& mw : work) {
      mw.h.setZero();
      mw.g.setZero();
      if (mw.stats.equations == 0) continue;
      const double lambda = mw.eq->model.weight / (mw.noise * mw.noise);
      for (size_t c = 0; c < mw.eq->cameras.size(); ++c) {
        const FlowEquations& eq = mw.eq->cameras[c];
        if (eq.size() == 0) continue;
        Matrix6d hc;
        Vector6d gc;
        Accumulate(eq, pass == 0 ? nullptr : &mw.weights[c], &hc, &gc);
        // twist_c = B twist with B = blockdiag(R_cw, R_cw): H = B^T Hc B, g = B^T gc.
        Matrix6d b = Matrix6d::Zero();
        const Eigen::Matrix3d r_cw = eq.world_from_cam_rotation.transpose();
        b.topLeftCorner<3, 3>() = r_cw;
        b.bottomRightCorner<3, 3>() = r_cw;
        mw.h.noalias() += lambda * (b.transpose() * hc * b);
        mw.g.noalias() += lambda * (b.transpose() * gc);
      }
      if (mw.eq->model.subordinate_ratio <= 0.0) lead += mw.h;
    }
    for (ModalityWork& mw : work) {
      if (mw.stats.equations == 0) continue;
      if (mw.eq->model.subordinate_ratio > 0.0 && lead.trace() > 0.0) {
        KeepWhereOpen(lead, mw.eq->model.subordinate_ratio, &mw.h, &mw.g);
      }
      h += mw.h;
      g += mw.g;
      modality_damping += mw.eq->model.damping * mw.h.trace() / 6.0;
    }
    const double trace = h.trace();
    if (!(trace > 0.0) || !std::isfinite(trace)) break;
    Matrix6d damped = h;
    damped.diagonal().array() += options.damping * trace / 6.0 + modality_damping;
    Eigen::LDLT<Matrix6d> ldlt(damped);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) break;
    const Vector6d x = ldlt.solve(g);
    if (!x.allFinite()) break;
    twist = x;
    information = damped;
    out.min_eigenvalue = Eigen::SelfAdjointEigenSolver<Matrix6d>(h, Eigen::EigenvaluesOnly)
                             .eigenvalues()(0);

    // Residuals of the linear model, normalized and in row units.
    for (ModalityWork& mw : work) {
      if (mw.stats.equations == 0) continue;
      mw.abs_normalized.resize(mw.stats.equations);
      mw.abs_row.resize(mw.stats.equations);
      float* abs_out = mw.abs_normalized.data();
      float* abs_row = mw.abs_row.data();
      double sum_sq = 0.0;
      for (size_t c = 0; c < mw.eq->cameras.size(); ++c) {
        const FlowEquations& eq = mw.eq->cameras[c];
        mw.weights[c].resize(eq.size());
        if (eq.size() == 0) continue;
        const Eigen::Matrix3d r_cw = eq.world_from_cam_rotation.transpose();
        Eigen::Matrix<float, 6, 1> tc;
        tc.head<3>() = (r_cw * twist.head<3>()).cast<float>();
        tc.tail<3>() = (r_cw * twist.tail<3>()).cast<float>();
        float* res = mw.weights[c].data();  // residuals for now, turned into weights below
        double camera_sum_sq = 0.0;        // a local, so that it stays in a register
        for (int i = 0; i < eq.size(); ++i) {
          const float e = eq.rows[i].dot(tc) - eq.rhs[i];
          const float r = e * eq.inv_grad_norm[i];
          res[i] = r;
          *abs_out++ = std::abs(r);
          *abs_row++ = std::abs(e);
          camera_sum_sq += double(r) * r;
        }
        sum_sq += camera_sum_sq;
      }
      mw.stats.final_rms = std::sqrt(sum_sq / mw.stats.equations);
      if (pass + 1 == solves) continue;
      const ResidualModel& model = mw.eq->model;
      const double scale = std::max(RobustSigma(&mw.abs_normalized), model.min_scale);
      mw.stats.robust_scale = scale;
      mw.noise = std::clamp(RobustSigma(&mw.abs_row), model.min_noise,
                            std::max(model.min_noise, model.max_noise));
      const double width = model.kernel_width * scale;
      for (auto& w : mw.weights) {
        for (float& v : w) v = static_cast<float>(Weight(model.kernel, v, width));
      }
    }
    if (pass + 1 == solves) out.ok = true;
  }
  for (ModalityWork& mw : work) mw.stats.noise = mw.noise;
  finish_stats();
  if (out.ok) {
    out.twist = twist;
    out.information = information;
  }
  return out;
}

FlowSolution SolveFlow(const std::vector<FlowEquations>& cameras,
                       const FlowSolverOptions& options) {
  ModalityEquations photometric;
  photometric.name = "photometric";
  photometric.model.kernel = options.kernel;
  photometric.model.kernel_width = options.kernel_width;
  photometric.model.min_scale = options.min_scale_px;
  photometric.cameras = cameras;
  return SolveJoint({&photometric}, options);
}

bool SwingsWithinNoise(const Vector6d& previous_update, const Vector6d& update,
                       const Matrix6d& information, double max_chi2) {
  const Vector6d information_update = information * update;
  return previous_update.dot(information_update) < 0.0 &&
         update.dot(information_update) < max_chi2;
}

}  // namespace unseen
