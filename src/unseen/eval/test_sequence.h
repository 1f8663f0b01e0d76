// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Test support (header only, used by the eval tests): a tiny synthetic one-camera sequence
// of a lettered cube over a grey background, with known ground truth.
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "unseen/eval/evaluation.h"
#include "unseen/io/pose_stream.h"
#include "unseen/io/sequence.h"
#include "unseen/mesh/primitives.h"
#include "unseen/render/rasterizer.h"

namespace unseen::testing {

struct TestSequence {
  std::string dir;
  Rig rig;                              // one camera "cam0", not at the world origin
  std::vector<Rigid3d> world_from_obj;  // per frame (frame id = index)
  Mesh mesh;                            // in metres
};

// The camera of the test sequence: 160x120, seen from 0.1 m right of the world origin.
inline Rig TestRig() {
  RigCamera camera;
  camera.name = "cam0";
  camera.intrinsics.width = 160;
  camera.intrinsics.height = 120;
  camera.intrinsics.fx = camera.intrinsics.fy = 150.0;
  camera.intrinsics.cx = 79.5;
  camera.intrinsics.cy = 59.5;
  camera.world_from_cam =
      Rigid3d(ExpSO3(Eigen::Vector3d(0.0, -0.1, 0.02)), Eigen::Vector3d(0.1, 0.0, 0.0));
  Rig rig;
  rig.cameras.push_back(camera);
  return rig;
}

// Writes `frames` frames to `dir` (replaced): the cube (edge 6 cm) moving and turning in
// front of the camera; ground truth written when `with_ground_truth`.
inline TestSequence WriteTestSequence(const std::string& dir, int frames,
                                      bool with_ground_truth = true) {
  std::filesystem::remove_all(dir);
  TestSequence seq;
  seq.dir = dir;
  seq.rig = TestRig();
  seq.mesh = MakeLetteredCube(0.06, 32);
  SequenceWriterOptions options;
  options.fps = 25.0;
  SequenceWriter writer(dir, seq.rig, options);
  writer.WriteModel(seq.mesh);
  const RigCamera& camera = seq.rig.cameras[0];
  for (int i = 0; i < frames; ++i) {
    const Rigid3d cam_from_obj(ExpSO3(Eigen::Vector3d(0.5 + 0.05 * i, 0.3 - 0.1 * i, 0.1)),
                               Eigen::Vector3d(-0.03 + 0.01 * i, 0.01, 0.45));
    const Rigid3d world_from_obj = camera.world_from_cam * cam_from_obj;
    seq.world_from_obj.push_back(world_from_obj);
    RenderBuffers buffers;
    Render(seq.mesh, camera.intrinsics, cam_from_obj, camera.intrinsics.ImageRect(), {}, &buffers);
    cv::Mat image(camera.intrinsics.height, camera.intrinsics.width, CV_32FC3,
                  cv::Scalar(0.5, 0.5, 0.5));
    buffers.color.copyTo(image, buffers.mask);
    writer.WriteFrame(i, {image}, {},
                      with_ground_truth ? std::optional<Rigid3d>(world_from_obj) : std::nullopt);
  }
  writer.Finish();
  return seq;
}

// Writes to `dir` (replaced) an RGB-D sequence of the test cube before a wall 1 m away; the ground truth of frames
// `first_wrong` on is written 3 cm deeper than where the cube is.
inline std::string WriteRgbdTestSequence(const std::string& dir, int frames, int first_wrong) {
  std::filesystem::remove_all(dir);
  const Rig rig = TestRig();
  const Mesh mesh = MakeLetteredCube(0.06, 32);
  SequenceWriterOptions options;
  options.fps = 25.0;
  SequenceWriter writer(dir, rig, options);
  writer.WriteModel(mesh);
  const RigCamera& camera = rig.cameras[0];
  for (int i = 0; i < frames; ++i) {
    const Rigid3d cam_from_obj(ExpSO3(Eigen::Vector3d(0.5 + 0.05 * i, 0.3 - 0.1 * i, 0.1)),
                               Eigen::Vector3d(-0.03 + 0.01 * i, 0.01, 0.45));
    RenderBuffers buffers;
    Render(mesh, camera.intrinsics, cam_from_obj, camera.intrinsics.ImageRect(), {}, &buffers);
    cv::Mat image(camera.intrinsics.height, camera.intrinsics.width, CV_32FC3,
                  cv::Scalar(0.5, 0.5, 0.5));
    buffers.color.copyTo(image, buffers.mask);
    cv::Mat depth(camera.intrinsics.height, camera.intrinsics.width, CV_32FC1, cv::Scalar(1.0));
    buffers.depth.copyTo(depth, buffers.mask);
    Rigid3d written = cam_from_obj;
    if (i >= first_wrong) {
      written = Rigid3d(cam_from_obj.rotation(),
                        cam_from_obj.translation() + Eigen::Vector3d(0.0, 0.0, 0.03));
    }
    writer.WriteFrame(i, {image}, {depth}, camera.world_from_cam * written);
  }
  writer.Finish();
  return dir;
}

// A pose stream that reports every ground-truth pose exactly (30 fps time stamps), with
// `process_ms` as each record's timing when given.
inline std::vector<PoseRecord> PerfectPoseStream(const std::vector<GroundTruthFrame>& gt,
                                                 std::optional<double> process_ms = {}) {
  std::vector<PoseRecord> records;
  for (const GroundTruthFrame& g : gt) {
    if (!g.world_from_obj) continue;
    PoseRecord r;
    r.frame = g.frame;
    r.time_s = g.frame / 30.0;
    r.world_from_obj = *g.world_from_obj;
    r.process_ms = process_ms;
    records.push_back(r);
  }
  return records;
}

// Whether mask pixel (x, y) is set and has a 4-neighbour outside the mask (or the image).
inline bool IsMaskBoundary(const cv::Mat& mask, int x, int y) {
  if (mask.at<uint8_t>(y, x) == 0) return false;
  const int dx[] = {1, -1, 0, 0}, dy[] = {0, 0, 1, -1};
  for (int k = 0; k < 4; ++k) {
    const int u = x + dx[k], v = y + dy[k];
    if (u < 0 || v < 0 || u >= mask.cols || v >= mask.rows) return true;
    if (mask.at<uint8_t>(v, u) == 0) return true;
  }
  return false;
}

}  // namespace unseen::testing
