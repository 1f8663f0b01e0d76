// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Test support (header only, used by the model tests): a rig of three cameras looking at
// the lettered cube before a textured wall, rendered 2x2 supersampled with exact depth.
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "unseen/camera/camera.h"
#include "unseen/io/sequence.h"
#include "unseen/mesh/mesh.h"
#include "unseen/mesh/primitives.h"
#include "unseen/render/rasterizer.h"

namespace unseen::testing {

struct RigScene {
  Rig rig;
  Mesh object;
  Rigid3d world_from_obj;
  Frame frame;                        // colour per camera, and exact depth per camera
  std::vector<cv::Mat> object_masks;  // per camera CV_8UC1, 255 where the object is seen
};

// Cameras: "left" at the origin, "right" 80 mm to its right, "top" 60 mm left and 50 mm up,
// all looking along +z (320x240, f = 400 px). The 100 mm cube 0.6 m ahead, turned to show
// three faces, before a wall 1 m away.
inline RigScene MakeRigScene() {
  RigScene s;
  const PinholeCamera cam = PinholeCamera::Centered(320, 240, 400.0);
  s.rig.cameras.push_back({"left", cam, Rigid3d()});
  s.rig.cameras.push_back(
      {"right", cam, Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.08, 0.0, 0.0))});
  s.rig.cameras.push_back(
      {"top", cam, Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-0.06, -0.05, 0.0))});
  s.object = MakeLetteredCube(0.1, 128);
  const Eigen::Quaterniond turn = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()) *
                                  Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitX()) *
                                  Eigen::Quaterniond::Identity();
  s.world_from_obj = Rigid3d(turn, Eigen::Vector3d(0.01, 0.0, 0.6));
  const Mesh wall = MakeTexturedBox(Eigen::Vector3d(1.6, 1.2, 0.02));
  const Rigid3d world_from_wall(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 1.0));
  for (const RigCamera& c : s.rig.cameras) {
    const PinholeCamera fine = c.intrinsics.Scaled(0.5);
    RenderBuffers wall_buffers, object_buffers;
    Render(wall, fine, c.cam_from_world() * world_from_wall, fine.ImageRect(), RenderOptions(),
           &wall_buffers);
    Render(s.object, fine, c.cam_from_world() * s.world_from_obj, fine.ImageRect(), RenderOptions(),
           &object_buffers);
    cv::Mat color = wall_buffers.color.clone();
    object_buffers.color.copyTo(color, object_buffers.mask);
    cv::Mat image;
    cv::resize(color, image, cv::Size(cam.width, cam.height), 0, 0, cv::INTER_AREA);
    // Depth and mask at the pixel centres' nearest fine sample.
    cv::Mat depth(cam.height, cam.width, CV_32FC1), mask(cam.height, cam.width, CV_8UC1);
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x) {
        const int fx = 2 * x + 1, fy = 2 * y + 1;
        const bool on_object = object_buffers.mask.at<uint8_t>(fy, fx) != 0;
        depth.at<float>(y, x) = on_object ? object_buffers.depth.at<float>(fy, fx)
                                          : wall_buffers.depth.at<float>(fy, fx);
        mask.at<uint8_t>(y, x) = on_object ? 255 : 0;
      }
    }
    s.frame.images.push_back(image);
    s.frame.depths.push_back(depth);
    s.object_masks.push_back(mask);
  }
  return s;
}

}  // namespace unseen::testing
