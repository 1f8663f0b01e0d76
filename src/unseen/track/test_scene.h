// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Test support (header only, used by the track tests): "camera images" made by rendering a
// model 2x2 supersampled over a smooth background, on the thesis camera.
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "unseen/camera/camera.h"
#include "unseen/mesh/mesh.h"
#include "unseen/mesh/primitives.h"
#include "unseen/render/rasterizer.h"

namespace unseen::testing {

// The thesis camera: 512x256, fx = fy = 837.3, centred.
inline PinholeCamera Camera512() { return PinholeCamera::Centered(512, 256, 837.3); }

// One such camera at the world origin, named "cam0".
inline Rig OneCameraRig() {
  Rig rig;
  rig.cameras.push_back({"cam0", Camera512(), Rigid3d()});
  return rig;
}

// A smooth, mildly textured background of `cam`'s size.
inline cv::Mat Background(const PinholeCamera& cam, int seed) {
  cv::RNG rng(seed);
  cv::Mat small(cam.height / 32 + 1, cam.width / 32 + 1, CV_32FC3);
  rng.fill(small, cv::RNG::UNIFORM, 0.3, 0.8);
  cv::Mat out;
  cv::resize(small, out, cv::Size(cam.width, cam.height), 0, 0, cv::INTER_CUBIC);
  return out;
}

// The lettered cube (96 mm) without its texture: one flat colour, no appearance.
inline Mesh FlatCube() {
  Mesh cube = MakeLetteredCube(0.096, 16);
  cube.uvs.clear();
  for (Material& m : cube.materials) {
    m.texture.release();
    m.diffuse_bgr = Eigen::Vector3f(0.55f, 0.35f, 0.25f);
  }
  return cube;
}

// `mesh` rendered at `world_from_obj` over `background`, 2x2 supersampled and averaged.
// With `gamma` > 1 the samples are averaged in linear light and the image is encoded with
// that gamma, as a camera integrates light; 1 averages the stored values.
inline cv::Mat RenderOverBackground(const Mesh& mesh, const RigCamera& camera,
                                    const Rigid3d& world_from_obj, const cv::Mat& background,
                                    double gamma = 1.0) {
  const PinholeCamera fine = camera.intrinsics.Scaled(0.5);
  RenderBuffers buffers;
  Render(mesh, fine, camera.cam_from_world() * world_from_obj, fine.ImageRect(), RenderOptions(),
         &buffers);
  cv::Mat big;
  cv::resize(background, big, cv::Size(fine.width, fine.height), 0, 0, cv::INTER_LINEAR);
  buffers.color.copyTo(big, buffers.mask);
  if (gamma != 1.0) cv::pow(cv::max(big, 0.0), gamma, big);
  cv::Mat out;
  cv::resize(big, out, cv::Size(camera.intrinsics.width, camera.intrinsics.height), 0, 0,
             cv::INTER_AREA);
  if (gamma != 1.0) cv::pow(out, 1.0 / gamma, out);
  return out;
}

// Metric depth of `mesh` at `world_from_obj` in front of a wall at `wall_m`, as an RGB-D
// camera registered to the colour camera measures it.
inline cv::Mat DepthImage(const Mesh& mesh, const RigCamera& camera, const Rigid3d& world_from_obj,
                          float wall_m) {
  RenderBuffers buffers;
  RenderOptions options;
  options.write_color = false;
  Render(mesh, camera.intrinsics, camera.cam_from_world() * world_from_obj,
         camera.intrinsics.ImageRect(), options, &buffers);
  cv::Mat depth(buffers.depth.size(), CV_32FC1, cv::Scalar(wall_m));
  buffers.depth.copyTo(depth, buffers.mask);
  return depth;
}

}  // namespace unseen::testing
