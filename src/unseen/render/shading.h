// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Lambertian shading for synthetic images (never used by the tracker, whose virtual image
// is the unshaded model colour, SPEC 3.1). The shaded colour of a visible surface point p
// with unit normal n and albedo a (the colour Render() gives) is
//
//   a * (ambient + sum_lights colour * intensity * max(0, n . l) * attenuation * visible)
//
// per channel, clamped to [0, 1]; l is the unit vector from p towards the light,
// attenuation is 1 for directional lights and 1 / d^2 (d in metres) for point lights, and
// `visible` is 0 or 1 from a shadow map (or a fraction at shadow edges).
//
// Frames: every light is given in the camera frame of the rendering camera (x right, y
// down, z forward). A caller with world-frame lights moves them with cam_from_world
// (positions) and its rotation (directions) for each camera.
//
// Shadows: each light with cast_shadows gets a depth map of `mesh` rendered with the CPU
// rasterizer from the light: a pinhole at the light looking at the mesh's bounding sphere
// for point lights, and a pinhole far away (50 bounding radii) along the light direction
// for directional lights (near-parallel rays, within 1.2 degrees). Only `mesh` casts
// shadows (merge meshes to let several objects shadow each other). A point light inside
// the bounding sphere casts no shadows (one frustum cannot hold the whole mesh).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "unseen/render/rasterizer.h"

namespace unseen {

struct DirectionalLight {
  Eigen::Vector3d direction_in_cam = Eigen::Vector3d::UnitZ();  // where the light travels
                                                                // (light -> scene); any length > 0
  Eigen::Vector3f color_bgr = Eigen::Vector3f::Ones();          // >= 0
  double intensity = 1.0;                                       // >= 0, multiplies color_bgr
  bool cast_shadows = false;
};

struct PointLight {
  Eigen::Vector3d position_in_cam = Eigen::Vector3d::Zero();  // metres
  Eigen::Vector3f color_bgr = Eigen::Vector3f::Ones();        // >= 0
  double intensity = 1.0;  // >= 0; the irradiance factor at 1 m, falling off as 1/d^2
  bool cast_shadows = false;
};

struct Lighting {
  Eigen::Vector3f ambient_bgr = Eigen::Vector3f::Constant(0.2f);  // >= 0
  std::vector<DirectionalLight> directional;
  std::vector<PointLight> point;
  // Throws unseen::Error naming the light and field for NaN, negative colour/intensity,
  // zero direction.
  void Check() const;
};

struct ShadingOptions {
  int shadow_map_px = 1024;       // side of each square shadow map, pixels [16, 8192]
  double shadow_bias_m = 1e-3;    // constant depth bias of the shadow test, metres (>= 0)
  double shadow_slope_bias = 2.0; // extra bias in shadow-map texels x tan(angle to light) (>= 0)
  bool two_sided = true;          // light back faces seen by the camera with flipped normals
  void Check() const;
};

// Renders `mesh` like Render() (same `roi`, `options`; colour and normals are always
// written) and replaces out->color by the shaded colour. out->normal holds the camera-
// frame normals used (flipped towards the camera when `two_sided`).
// Throws unseen::Error for invalid input (mesh, camera, pose, lighting, options).
void RenderShaded(const Mesh& mesh, const PinholeCamera& camera, const Rigid3d& cam_from_obj,
                  const PixelRect& roi, const Lighting& lighting, const RenderOptions& options,
                  const ShadingOptions& shading, RenderBuffers* out);

}  // namespace unseen
