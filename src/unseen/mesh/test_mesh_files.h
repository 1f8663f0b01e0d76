// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Test support (header only, used by the mesh reading and writing tests): a fresh folder
// per test, a two-colour texture, and comparisons of meshes by their surface colours.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "unseen/mesh/mesh.h"
#include "unseen/util/error.h"

namespace unseen::testing {

// A fresh folder per test, removed afterwards.
class MeshIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("unseen_mesh_io_" + std::string(info->name()) + "_" + std::to_string(getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string ReadFile(const std::string& path) const {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), {});
  }
  std::string Write(const std::string& name, const std::string& text) const {
    std::ofstream(Path(name), std::ios::binary) << text;
    return Path(name);
  }

  std::filesystem::path dir_;
};

// An 8x8 texture whose top half (image rows 0-3) is red and bottom half blue.
inline cv::Mat TopRedBottomBlue() {
  cv::Mat image(8, 8, CV_8UC3, cv::Scalar(255, 0, 0));  // BGR blue
  image.rowRange(0, 4).setTo(cv::Scalar(0, 0, 255));    // red
  return image;
}

inline bool IsRed(const cv::Vec3f& c) { return c[2] > 0.9f && c[0] < 0.1f && c[1] < 0.1f; }
inline bool IsBlue(const cv::Vec3f& c) { return c[0] > 0.9f && c[2] < 0.1f && c[1] < 0.1f; }

// Bilinear texture lookup with the OBJ convention: column u * cols, row (1 - v) * rows.
inline cv::Vec3f SampleUv(const cv::Mat& texture, const Eigen::Vector2f& uv) {
  const float x = uv.x() * texture.cols - 0.5f;
  const float y = (1.0f - uv.y()) * texture.rows - 0.5f;
  const int x0 = std::clamp(static_cast<int>(std::floor(x)), 0, texture.cols - 1);
  const int y0 = std::clamp(static_cast<int>(std::floor(y)), 0, texture.rows - 1);
  const int x1 = std::min(x0 + 1, texture.cols - 1);
  const int y1 = std::min(y0 + 1, texture.rows - 1);
  const float fx = std::clamp(x - x0, 0.0f, 1.0f);
  const float fy = std::clamp(y - y0, 0.0f, 1.0f);
  return (1 - fy) *
             ((1 - fx) * texture.at<cv::Vec3f>(y0, x0) + fx * texture.at<cv::Vec3f>(y0, x1)) +
         fy * ((1 - fx) * texture.at<cv::Vec3f>(y1, x0) + fx * texture.at<cv::Vec3f>(y1, x1));
}

// The colour the renderer would show at barycentric point `bary` of triangle t (texture,
// else vertex colour, else material colour).
inline cv::Vec3f SurfaceColour(const Mesh& mesh, int t, const Eigen::Vector3f& bary) {
  const Eigen::Vector3i& tri = mesh.triangles[t];
  const int m = mesh.triangle_materials.empty() ? 0 : mesh.triangle_materials[t];
  if (!mesh.uvs.empty() && !mesh.materials[m].texture.empty()) {
    const Eigen::Vector2f uv =
        bary[0] * mesh.uvs[tri[0]] + bary[1] * mesh.uvs[tri[1]] + bary[2] * mesh.uvs[tri[2]];
    return SampleUv(mesh.materials[m].texture, uv);
  }
  if (!mesh.colors_bgr.empty()) {
    const Eigen::Vector3f c = bary[0] * mesh.colors_bgr[tri[0]] +
                              bary[1] * mesh.colors_bgr[tri[1]] + bary[2] * mesh.colors_bgr[tri[2]];
    return {c[0], c[1], c[2]};
  }
  const Eigen::Vector3f& d = mesh.materials[m].diffuse_bgr;
  return {d[0], d[1], d[2]};
}

// Triangle whose three vertices match `other`'s triangle t in position (same order).
inline int FindTriangle(const Mesh& mesh, const Mesh& other, int t, float tolerance) {
  for (int s = 0; s < mesh.num_triangles(); ++s) {
    bool same = true;
    for (int k = 0; k < 3 && same; ++k) {
      same = (mesh.vertices[mesh.triangles[s][k]] - other.vertices[other.triangles[t][k]]).norm() <
             tolerance;
    }
    if (same) return s;
  }
  return -1;
}

// Same triangles (same winding) and the same surface colour at several points of each.
inline void ExpectSameAppearance(const Mesh& expected, const Mesh& actual, float colour_tolerance) {
  ASSERT_EQ(expected.num_triangles(), actual.num_triangles());
  const Eigen::Vector3f points[] = {
      {1 / 3.f, 1 / 3.f, 1 / 3.f}, {0.7f, 0.2f, 0.1f}, {0.1f, 0.7f, 0.2f}, {0.2f, 0.1f, 0.7f}};
  for (int t = 0; t < expected.num_triangles(); ++t) {
    const int s = FindTriangle(actual, expected, t, 1e-5f);
    ASSERT_GE(s, 0) << "triangle " << t << " not found";
    for (const Eigen::Vector3f& bary : points) {
      const cv::Vec3f a = SurfaceColour(expected, t, bary);
      const cv::Vec3f b = SurfaceColour(actual, s, bary);
      EXPECT_LT(cv::norm(a - b), colour_tolerance)
          << "triangle " << t << " at " << bary.transpose();
    }
  }
}

// Every triangle faces away from the origin (convex objects centred on it).
inline void ExpectOutward(const Mesh& mesh) {
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    const Eigen::Vector3f& a = mesh.vertices[tri[0]];
    const Eigen::Vector3f n = (mesh.vertices[tri[1]] - a).cross(mesh.vertices[tri[2]] - a);
    EXPECT_GT(n.dot(a + mesh.vertices[tri[1]] + mesh.vertices[tri[2]]), 0.0f) << "triangle " << t;
  }
}

// Textures are not mirrored seen from outside: on every triangle the uv frame (u right,
// v up) has the same handedness as the surface seen from outside, i.e.
// (dP/du x dP/dv) . n > 0 with n the triangle's outward (right-hand-rule) normal.
inline void ExpectTexturesNotMirrored(const Mesh& mesh) {
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    const Eigen::Vector3f e1 = mesh.vertices[tri[1]] - mesh.vertices[tri[0]];
    const Eigen::Vector3f e2 = mesh.vertices[tri[2]] - mesh.vertices[tri[0]];
    const Eigen::Vector2f d1 = mesh.uvs[tri[1]] - mesh.uvs[tri[0]];
    const Eigen::Vector2f d2 = mesh.uvs[tri[2]] - mesh.uvs[tri[0]];
    // [e1 e2] = [dP/du dP/dv] [d1 d2]; the sign of det[d1 d2] says whether the uv
    // triangle is counter-clockwise like the 3-D one seen from outside.
    const float uv_area = d1.x() * d2.y() - d1.y() * d2.x();
    ASSERT_GT(e1.cross(e2).norm(), 0.0f);
    EXPECT_GT(uv_area, 0.0f) << "triangle " << t << " maps its texture mirrored";
  }
}

inline void ExpectThrowsMentioning(const std::function<void()>& f, const std::vector<std::string>& words) {
  try {
    f();
    ADD_FAILURE() << "no unseen::Error thrown";
  } catch (const Error& e) {
    for (const std::string& w : words) {
      EXPECT_NE(std::string(e.what()).find(w), std::string::npos)
          << "message '" << e.what() << "' does not mention '" << w << "'";
    }
  }
}

// A unit quad in the z = 0 plane facing +z; vt (0, 0) at the bottom-left corner.
inline constexpr const char* kQuadObj = R"(mtllib quad.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
usemtl tex
f 1/1 2/2 3/3
f 1/1 3/3 4/4
)";

}  // namespace unseen::testing
