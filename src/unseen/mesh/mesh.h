// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Textured triangle meshes in the object frame, in metres. A mesh is coloured by one of:
//  * UV textures (per-vertex uv into the texture of each triangle's material),
//  * per-vertex colours,
//  * projective textures (SPEC 5.3): images with the projector's intrinsics and pose in
//    the object frame — what the on-line modeller produces. Several may be stored.
// Colours are BGR float in [0, 1] (OpenCV order), like every image in unseen.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"

namespace unseen {

struct Material {
  std::string name;
  Eigen::Vector3f diffuse_bgr = Eigen::Vector3f::Ones();  // used where there is no texture
  cv::Mat texture;           // CV_32FC3 BGR [0, 1], or empty
  std::string texture_path;  // file the texture came from / is saved to (relative)
};

// A camera image that textures the mesh by projection, fixed to the object.
struct Projector {
  cv::Mat image;          // CV_32FC3 BGR [0, 1]
  PinholeCamera camera;   // intrinsics of `image`
  Rigid3d cam_from_obj;   // where the projector was, in the object frame
  // Optional: CV_32FC1 of the size of `image`, the projector's z (metres) of the surface it
  // saw, 0 where it saw none. With it, a point more than depth_tolerance_m behind that
  // surface, or where it saw none, is hidden from the projector (self-occlusion); without
  // it, every point in front of the projector and facing it takes its colour.
  cv::Mat depth;
  float depth_tolerance_m = 0.003f;
};

struct Mesh {
  std::vector<Eigen::Vector3f> vertices;   // object frame, metres
  std::vector<Eigen::Vector3i> triangles;  // counter-clockwise seen from outside
  std::vector<Eigen::Vector3f> normals;    // per vertex, unit; empty = compute when needed
  std::vector<Eigen::Vector2f> uvs;        // per vertex, texture coords (v up, OBJ style); or empty
  std::vector<Eigen::Vector3f> colors_bgr; // per vertex in [0, 1]; or empty
  std::vector<int> triangle_materials;     // per triangle index into materials; or empty
  std::vector<Material> materials;
  std::vector<Projector> projectors;       // non-empty: projective texturing

  int num_vertices() const { return static_cast<int>(vertices.size()); }
  int num_triangles() const { return static_cast<int>(triangles.size()); }
  bool HasUvTexture() const;
  // True when the surface's colour varies: a UV texture, projective textures, vertex
  // colours that differ, or materials of different diffuse colours. A mesh without
  // appearance renders in one flat colour.
  bool HasAppearance() const;

  // Throws unseen::Error naming `what` for: no triangles, non-finite vertices, indices out
  // of range, attribute arrays whose size does not match, material ids out of range.
  void Check(const std::string& what = "mesh") const;

  // Smallest sphere around the vertices' bounding-box centre containing every vertex.
  void BoundingSphere(Eigen::Vector3f* centre, float* radius) const;
  // Axis-aligned bounds.
  void BoundingBox(Eigen::Vector3f* min, Eigen::Vector3f* max) const;

  // Multiplies vertex positions (and projector translations and depths) by s.
  void Scale(float s);
  // Area-weighted vertex normals from the triangles.
  void ComputeNormals();
  // Drops the vertices no triangle uses, with their attributes; renumbers the triangles.
  void RemoveUnusedVertices();
};

}  // namespace unseen
