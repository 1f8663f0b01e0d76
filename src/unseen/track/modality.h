// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The interface every tracking modality sits behind (SPEC 3.9). A render-solve round of the
// tracker renders the model at the round's pose for each camera and hands each modality
// the same view of it (ModalityRound); the modality appends its rows, in the optical-flow
// row form of flow_jacobian.h, to its own equations, and counts what it saw. The tracker
// solves all modalities' equations in one Gauss-Newton step (flow_solver.h, SolveJoint),
// each weighed by its measured noise, and judges the frame by their counts.
//
// Modalities: photometric (photometric_modality.h: the thesis's optical flow between the
// virtual and the input image), depth (depth_modality.h: point-to-plane against measured
// depth), region (region_modality.h: the silhouette against learnt colour statistics).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/track/flow_solver.h"
#include "unseen/track/preprocess.h"
#include "unseen/track/virtual_image.h"

namespace unseen {

// One camera's share of a round: the model rendered at the round's pose over the level's
// region of interest of the frame. Buffers are of the size of `roi` unless said.
struct ModalityRound {
  int camera = 0;  // rig index
  int level = 0;   // pyramid level
  PixelRect roi;   // level pixels: buffer (0, 0) is pixel (roi.x0, roi.y0)
  PinholeCamera level_camera;
  PinholeCamera camera_intrinsics;  // the full-resolution camera
  Eigen::Matrix3d world_from_cam_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d origin_in_cam = Eigen::Vector3d::Zero();  // object origin, camera frame
  const VirtualImage* virtual_image = nullptr;  // composite, mask, depth, coverage
  const cv::Mat* input = nullptr;               // CV_32FC3 BGR [0, 1]: the level's input
  // The photometric modality's: both images pre-processed, the pixels it may use (mask and
  // rim) and their depth.
  const PreprocessedImage* virtual_pre = nullptr;
  const PreprocessedImage* input_pre = nullptr;
  const cv::Mat* photometric_region = nullptr;
  const cv::Mat* photometric_depth = nullptr;
  // The blocks of this round's roi that the photometric modality found occluded (CV_8UC1,
  // non-zero: an occluder in front of the object; PhotometricModality::occluded_blocks),
  // occluded_block_px level pixels a side; null when it did not look.
  const cv::Mat* occluded_blocks = nullptr;
  int occluded_block_px = 0;
  // CV_32FC1 metres at full resolution (0: none) when the frame carries depth, else null.
  const cv::Mat* measured_depth = nullptr;
  // The statistics a modality learns may learn from this round (the tracker's choice: the
  // finest level); `first_frame`: the frame after Initialize(), at the given pose.
  bool learn = false;
  bool first_frame = false;
  // A frame's alignment from its predicted pose (not a search's) without the photometric
  // modality: the silhouette (and depth) track alone.
  bool without_texture = false;
};

class Modality {
 public:
  explicit Modality(std::string name) { equations_.name = std::move(name); }
  virtual ~Modality() = default;
  Modality(const Modality&) = default;
  Modality& operator=(const Modality&) = default;

  const std::string& name() const { return equations_.name; }
  // Robust kernel, noise bounds and weight of the rows in the joint solve.
  ResidualModel& residual_model() { return equations_.model; }
  // Start of a round for `num_cameras` cameras: no rows, nothing counted.
  virtual void BeginRound(int num_cameras) {
    equations_.cameras.resize(num_cameras);
    for (FlowEquations& eq : equations_.cameras) eq.Clear();
    round_rhs_.clear();
  }
  // Appends camera `round.camera`'s rows (rows in that camera's frame) and counts. Calls
  // for different cameras of a round may run concurrently.
  virtual void AddEquations(const ModalityRound& round) = 0;
  // The pose has moved by `twist_in_cam[c]` since the round was rendered (camera c's frame:
  // (v_c, w_c) about the object's origin at the round's pose): the rows' right-hand sides
  // become what they measure there, so that the round's rows can be solved again without a
  // new render (a Gauss-Newton step on the round's linearisation). This default follows
  // each row's linear model, b - a . twist; a modality that can measure again overrides it.
  virtual void MoveBy(const std::vector<Vector6d>& twist_in_cam);
  const ModalityEquations& equations() const { return equations_; }

 protected:
  FlowEquations& CameraEquations(const ModalityRound& round) {
    FlowEquations& eq = equations_.cameras[round.camera];
    eq.world_from_cam_rotation = round.world_from_cam_rotation;
    return eq;
  }
  FlowEquations& CameraEquations(int camera) { return equations_.cameras[camera]; }
  // Camera c's right-hand sides as the round built them (saved by the first MoveBy).
  const std::vector<float>& RoundRhs(int camera);

 private:
  ModalityEquations equations_;
  std::vector<std::vector<float>> round_rhs_;  // per camera; empty until the first MoveBy
};

// A modality whose counts (Counts: summable with +=) are kept per camera and summed.
template <typename Counts>
class CountingModality : public Modality {
 public:
  using Modality::Modality;
  void BeginRound(int num_cameras) override {
    Modality::BeginRound(num_cameras);
    camera_counts_.assign(num_cameras, Counts());
  }
  // What the round's cameras saw, summed.
  Counts counts() const {
    Counts sum;
    for (const Counts& c : camera_counts_) sum += c;
    return sum;
  }

 protected:
  Counts& CameraCounts(const ModalityRound& round) { return camera_counts_[round.camera]; }

 private:
  std::vector<Counts> camera_counts_;
};

}  // namespace unseen
