// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/mesh/mesh.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "unseen/mesh/primitives.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

// A unit right tetrahedron, triangles counter-clockwise seen from outside.
Mesh Tetrahedron() {
  Mesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return mesh;
}

void ExpectCheckFails(const Mesh& mesh, const std::string& fragment) {
  try {
    mesh.Check("model.ply");
    ADD_FAILURE() << "Check accepted a mesh that should fail with '" << fragment << "'";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("model.ply"), std::string::npos) << message;
    EXPECT_NE(message.find(fragment), std::string::npos) << message;
  }
}

TEST(MeshCheck, AcceptsValidMeshes) {
  EXPECT_NO_THROW(Tetrahedron().Check());
  EXPECT_NO_THROW(MakeLetteredCube(0.1, 32).Check());
}

TEST(MeshCheck, RejectsEachKindOfBrokenMesh) {
  Mesh no_triangles = Tetrahedron();
  no_triangles.triangles.clear();
  ExpectCheckFails(no_triangles, "no triangles");

  Mesh nan_vertex = Tetrahedron();
  nan_vertex.vertices[2].y() = std::numeric_limits<float>::quiet_NaN();
  ExpectCheckFails(nan_vertex, "vertex 2");

  Mesh infinite_vertex = Tetrahedron();
  infinite_vertex.vertices[3].z() = std::numeric_limits<float>::infinity();
  ExpectCheckFails(infinite_vertex, "vertex 3");

  Mesh nan_uv = Tetrahedron();
  nan_uv.uvs.assign(4, Eigen::Vector2f(0.5f, 0.5f));
  nan_uv.uvs[1].y() = std::numeric_limits<float>::quiet_NaN();
  ExpectCheckFails(nan_uv, "texture coordinate 1");

  Mesh index_high = Tetrahedron();
  index_high.triangles[1][2] = 4;
  ExpectCheckFails(index_high, "index 4 out of range");

  Mesh index_negative = Tetrahedron();
  index_negative.triangles[0][0] = -1;
  ExpectCheckFails(index_negative, "index -1");

  Mesh normals = Tetrahedron();
  normals.normals.resize(3);
  ExpectCheckFails(normals, "3 normals for 4 vertices");

  Mesh uvs = Tetrahedron();
  uvs.uvs.resize(5);
  ExpectCheckFails(uvs, "5 uvs");

  Mesh colours = Tetrahedron();
  colours.colors_bgr.resize(1);
  ExpectCheckFails(colours, "1 colours");

  Mesh material_count = Tetrahedron();
  material_count.materials.resize(1);
  material_count.triangle_materials = {0, 0};
  ExpectCheckFails(material_count, "2 triangle materials for 4 triangles");

  Mesh material_range = Tetrahedron();
  material_range.materials.resize(1);
  material_range.triangle_materials = {0, 0, 1, 0};
  ExpectCheckFails(material_range, "material 1 out of range");

  Mesh texture_type = Tetrahedron();
  texture_type.materials.resize(1);
  texture_type.materials[0].name = "wood";
  texture_type.materials[0].texture = cv::Mat(4, 4, CV_8UC3);
  ExpectCheckFails(texture_type, "wood");

  Mesh projector = Tetrahedron();
  projector.projectors.resize(1);
  ExpectCheckFails(projector, "projector 0");

  // A projector's depth map must match its image; its occlusion tolerance must be >= 0.
  Mesh depth = Tetrahedron();
  depth.projectors.resize(1);
  depth.projectors[0].image = cv::Mat(8, 8, CV_32FC3, cv::Scalar::all(0.5));
  depth.projectors[0].camera = PinholeCamera::Centered(8, 8, 10.0);
  depth.projectors[0].depth = cv::Mat(4, 8, CV_32FC1, cv::Scalar(1.0f));
  ExpectCheckFails(depth, "projector 0 depth");
  depth.projectors[0].depth = cv::Mat(8, 8, CV_32FC1, cv::Scalar(1.0f));
  EXPECT_NO_THROW(depth.Check("model.ply"));
  depth.projectors[0].depth_tolerance_m = std::numeric_limits<float>::quiet_NaN();
  ExpectCheckFails(depth, "depth_tolerance_m");
}

TEST(MeshBounds, BoxAndSphere) {
  Mesh mesh = Tetrahedron();
  for (Eigen::Vector3f& v : mesh.vertices) v += Eigen::Vector3f(1, 2, 3);
  Eigen::Vector3f lo, hi;
  mesh.BoundingBox(&lo, &hi);
  EXPECT_TRUE(lo.isApprox(Eigen::Vector3f(1, 2, 3)));
  EXPECT_TRUE(hi.isApprox(Eigen::Vector3f(2, 3, 4)));
  Eigen::Vector3f centre;
  float radius;
  mesh.BoundingSphere(&centre, &radius);
  EXPECT_TRUE(centre.isApprox(Eigen::Vector3f(1.5f, 2.5f, 3.5f)));
  // The farthest vertex from the box centre is the corner (1, 2, 3): sqrt(3) / 2.
  EXPECT_NEAR(radius, std::sqrt(3.0f) / 2.0f, 1e-6f);
  for (const Eigen::Vector3f& v : mesh.vertices) EXPECT_LE((v - centre).norm(), radius + 1e-6f);
}

TEST(MeshNormals, AreaWeightedAndOutward) {
  // Cube without per-vertex normals: corner normals point along the diagonal.
  Mesh cube = MakeLetteredCube(2.0, 16);
  cube.normals.clear();
  cube.ComputeNormals();
  ASSERT_EQ(cube.normals.size(), cube.vertices.size());
  for (size_t v = 0; v < cube.vertices.size(); ++v) {
    EXPECT_NEAR(cube.normals[v].norm(), 1.0f, 1e-5f);
    // Faces have their own vertices, so each normal is its face's normal: one axis.
    const Eigen::Vector3f abs_n = cube.normals[v].cwiseAbs();
    EXPECT_NEAR(abs_n.maxCoeff(), 1.0f, 1e-5f);
    EXPECT_GT(cube.normals[v].dot(cube.vertices[v]), 0.0f);
  }
  // Shared-vertex tetrahedron: the apex (0,0,1) joins two unit-area-1/2 faces (normals -x,
  // -y) and the slanted face (area sqrt(3)/2, normal (1,1,1)/sqrt(3)): sum (0, 0, 1).
  Mesh tet = Tetrahedron();
  tet.ComputeNormals();
  EXPECT_TRUE(tet.normals[3].isApprox(Eigen::Vector3f(0, 0, 1), 1e-5f)) << tet.normals[3];
  // The origin joins the three axis faces equally: -(1,1,1)/sqrt(3).
  EXPECT_TRUE(tet.normals[0].isApprox(-Eigen::Vector3f::Ones().normalized(), 1e-5f));
}

TEST(MeshNormals, IsolatedVertexGetsAUnitNormal) {
  Mesh mesh = Tetrahedron();
  mesh.vertices.emplace_back(5, 5, 5);  // referenced by no triangle
  mesh.ComputeNormals();
  EXPECT_NEAR(mesh.normals[4].norm(), 1.0f, 1e-6f);
}

TEST(MeshScale, ScalesVerticesAndProjectorTranslationsAndDepths) {
  Mesh mesh = Tetrahedron();
  Projector p;
  p.cam_from_obj = Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY())),
                           Eigen::Vector3d(10, 20, 300));
  p.depth = cv::Mat(2, 2, CV_32FC1, cv::Scalar(400.0f));
  p.depth_tolerance_m = 3.0f;
  mesh.projectors.push_back(p);
  mesh.Scale(0.001f);
  EXPECT_TRUE(mesh.vertices[1].isApprox(Eigen::Vector3f(0.001f, 0, 0)));
  EXPECT_FLOAT_EQ(mesh.projectors[0].depth.at<float>(1, 1), 0.4f);
  EXPECT_FLOAT_EQ(mesh.projectors[0].depth_tolerance_m, 0.003f);
  EXPECT_TRUE(mesh.projectors[0].cam_from_obj.translation().isApprox(
      Eigen::Vector3d(0.01, 0.02, 0.3), 1e-6));
  EXPECT_TRUE(mesh.projectors[0].cam_from_obj.rotation().isApprox(p.cam_from_obj.rotation()));
}

TEST(MeshTexture, HasUvTextureNeedsUvsAndATexture) {
  Mesh mesh = Tetrahedron();
  EXPECT_FALSE(mesh.HasUvTexture());
  mesh.materials.resize(1);
  mesh.materials[0].texture = cv::Mat(2, 2, CV_32FC3, cv::Scalar(1, 1, 1));
  EXPECT_FALSE(mesh.HasUvTexture());  // no uvs
  mesh.uvs.assign(4, Eigen::Vector2f(0.5f, 0.5f));
  EXPECT_TRUE(mesh.HasUvTexture());
  EXPECT_EQ(mesh.num_vertices(), 4);
  EXPECT_EQ(mesh.num_triangles(), 4);
}

}  // namespace
}  // namespace unseen
