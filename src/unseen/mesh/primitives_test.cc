// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/mesh/primitives.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <set>

#include "unseen/util/error.h"

namespace unseen {
namespace {

// Every triangle's right-hand-rule normal points away from the centre (convex shapes
// centred on the origin), and no triangle is degenerate.
void ExpectOutwardTriangles(const Mesh& mesh) {
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    const Eigen::Vector3f& a = mesh.vertices[tri[0]];
    const Eigen::Vector3f& b = mesh.vertices[tri[1]];
    const Eigen::Vector3f& c = mesh.vertices[tri[2]];
    const Eigen::Vector3f n = (b - a).cross(c - a);
    ASSERT_GT(n.norm(), 0.0f) << "degenerate triangle " << t;
    const Eigen::Vector3f centroid = (a + b + c) / 3.0f;
    EXPECT_GT(n.dot(centroid), 0.0f) << "triangle " << t << " faces inwards";
  }
}

// Textures read correctly (not mirrored) seen from outside: each triangle's uv triangle is
// counter-clockwise like the triangle itself seen from outside.
void ExpectTexturesNotMirrored(const Mesh& mesh) {
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    const Eigen::Vector2f d1 = mesh.uvs[tri[1]] - mesh.uvs[tri[0]];
    const Eigen::Vector2f d2 = mesh.uvs[tri[2]] - mesh.uvs[tri[0]];
    EXPECT_GT(d1.x() * d2.y() - d1.y() * d2.x(), 0.0f) << "triangle " << t;
  }
}

// Texture variation: standard deviation of the grey texture's Sobel gradient magnitude.
double MeanGradient(const cv::Mat& texture) {
  cv::Mat grey, gx, gy, mag;
  cv::cvtColor(texture, grey, cv::COLOR_BGR2GRAY);
  cv::Sobel(grey, gx, CV_32F, 1, 0);
  cv::Sobel(grey, gy, CV_32F, 0, 1);
  cv::magnitude(gx, gy, mag);
  return cv::mean(mag)[0];
}

TEST(LetteredCube, GeometryAndMaterials) {
  const Mesh cube = MakeLetteredCube(0.096, 128);
  EXPECT_NO_THROW(cube.Check("cube"));
  EXPECT_EQ(cube.num_vertices(), 24);
  EXPECT_EQ(cube.num_triangles(), 12);
  EXPECT_EQ(cube.uvs.size(), 24u);
  ASSERT_EQ(cube.materials.size(), 6u);
  EXPECT_TRUE(cube.HasUvTexture());
  Eigen::Vector3f lo, hi;
  cube.BoundingBox(&lo, &hi);
  EXPECT_TRUE(lo.isApprox(Eigen::Vector3f::Constant(-0.048f)));
  EXPECT_TRUE(hi.isApprox(Eigen::Vector3f::Constant(0.048f)));
  ExpectOutwardTriangles(cube);
  ExpectTexturesNotMirrored(cube);
  for (const Eigen::Vector2f& uv : cube.uvs) {
    EXPECT_TRUE((uv.array() >= 0.0f).all() && (uv.array() <= 1.0f).all());
  }
  std::set<std::string> names;
  for (const Material& m : cube.materials) {
    names.insert(m.name);
    ASSERT_EQ(m.texture.type(), CV_32FC3);
    EXPECT_EQ(m.texture.rows, 128);
    EXPECT_GT(MeanGradient(m.texture), 0.05) << m.name;
  }
  EXPECT_EQ(names.size(), 6u);
}

TEST(LetteredCube, FacesHaveDistinctColoursAndDocumentedOrder) {
  const Mesh cube = MakeLetteredCube(1.0, 64);
  const Eigen::Vector3f expected_normals[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                               {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
  for (int t = 0; t < cube.num_triangles(); ++t) {
    const int m = cube.triangle_materials[t];
    EXPECT_EQ(cube.materials[m].name, std::string("face_") + char('A' + m));
    const Eigen::Vector3i& tri = cube.triangles[t];
    const Eigen::Vector3f n = (cube.vertices[tri[1]] - cube.vertices[tri[0]])
                                  .cross(cube.vertices[tri[2]] - cube.vertices[tri[0]])
                                  .normalized();
    EXPECT_TRUE(n.isApprox(expected_normals[m], 1e-5f)) << "triangle " << t;
  }
  // Background (the texel at 1/4 from the corner, outside letter and frame) differs
  // strongly between every pair of faces.
  for (int a = 0; a < 6; ++a) {
    for (int b = a + 1; b < 6; ++b) {
      const cv::Vec3f ca = cube.materials[a].texture.at<cv::Vec3f>(3, 3);
      const cv::Vec3f cb = cube.materials[b].texture.at<cv::Vec3f>(3, 3);
      EXPECT_GT(cv::norm(ca - cb), 0.3) << a << " vs " << b;
    }
  }
}

TEST(LetteredCube, LetterIsUpright) {
  // The letter "A" is wider at its foot than at its apex. With the OBJ convention (row =
  // (1 - v) * rows) the foot is at small v, which is the face's "up" direction's bottom.
  const Mesh cube = MakeLetteredCube(1.0, 256);
  const cv::Mat& tex = cube.materials[0].texture;
  const cv::Vec3f bg = tex.at<cv::Vec3f>(40, 128);  // inside the frame, above the letter
  auto letter_width = [&](int row) {
    int count = 0;
    for (int x = 32; x < 224; ++x) count += cv::norm(tex.at<cv::Vec3f>(row, x) - bg) > 0.5;
    return count;
  };
  // The letter spans roughly rows 50..206 for a 256 px face.
  int top = -1, bottom = -1;
  for (int y = 32; y < 224; ++y) {
    if (letter_width(y) > 0) {
      if (top < 0) top = y;
      bottom = y;
    }
  }
  ASSERT_GT(top, 0);
  ASSERT_GT(bottom, top + 50);
  const int near_top = letter_width(top + 8);
  const int near_bottom = letter_width(bottom - 8);
  EXPECT_GT(near_bottom, near_top);  // spread legs at the bottom of the image
  // Image bottom is v = 0: those texels are addressed by the face's bottom vertices,
  // which lie towards -z on the side faces.
  for (int k = 0; k < 4; ++k) {
    const int vi = k;  // first face (+x) vertices 0..3
    if (cube.uvs[vi].y() < 0.5f) {
      EXPECT_LT(cube.vertices[vi].z(), 0.0f);
    } else {
      EXPECT_GT(cube.vertices[vi].z(), 0.0f);
    }
  }
}

TEST(LetteredCube, RejectsBadArguments) {
  EXPECT_THROW(MakeLetteredCube(0.0), Error);
  EXPECT_THROW(MakeLetteredCube(-1.0), Error);
  EXPECT_THROW(MakeLetteredCube(std::nan("")), Error);
  EXPECT_THROW(MakeLetteredCube(0.1, 4), Error);
}

TEST(TexturedSphere, TriangleCountRadiusAndOrientation) {
  const int rings = 25, segments = 50;
  const Mesh sphere = MakeTexturedSphere(0.03, rings, segments);
  EXPECT_NO_THROW(sphere.Check("sphere"));
  EXPECT_EQ(sphere.num_triangles(), 2 * rings * segments - 2 * segments);
  for (const Eigen::Vector3f& v : sphere.vertices) EXPECT_NEAR(v.norm(), 0.03f, 1e-6f);
  ExpectOutwardTriangles(sphere);
  ExpectTexturesNotMirrored(sphere);
  for (size_t i = 0; i < sphere.normals.size(); ++i) {
    EXPECT_NEAR(sphere.normals[i].dot(sphere.vertices[i].normalized()), 1.0f, 1e-5f);
  }
  Eigen::Vector3f centre;
  float radius;
  sphere.BoundingSphere(&centre, &radius);
  EXPECT_LT(centre.norm(), 1e-6f);
  EXPECT_NEAR(radius, 0.03f, 1e-6f);
  ASSERT_EQ(sphere.materials.size(), 1u);
  EXPECT_TRUE(sphere.HasUvTexture());
}

TEST(TexturedSphere, UvsFollowEquirectangularMapping) {
  const Mesh sphere = MakeTexturedSphere(1.0, 8, 16);
  for (int i = 0; i < sphere.num_vertices(); ++i) {
    const Eigen::Vector3f& p = sphere.vertices[i];
    const Eigen::Vector2f& uv = sphere.uvs[i];
    ASSERT_TRUE((uv.array() >= 0.0f).all() && (uv.array() <= 1.0f).all());
    // v = 1 at the north pole (+z), 0 at the south pole.
    EXPECT_NEAR(uv.y(), 1.0f - std::acos(std::clamp(p.z(), -1.0f, 1.0f)) / M_PI, 1e-5);
  }
}

TEST(TexturedSphere, BenchmarkSizes) {
  // The renderer benchmarks use about 2 500 and 100 000 triangles.
  EXPECT_EQ(MakeTexturedSphere(0.03, 26, 50).num_triangles(), 2500);
  EXPECT_EQ(MakeTexturedSphere(0.03, 224, 224).num_triangles(), 99904);
}

TEST(TexturedSphere, DefaultTextureIsDeterministicAndTextured) {
  const Mesh a = MakeTexturedSphere(0.03, 4, 8);
  const Mesh b = MakeTexturedSphere(0.03, 4, 8);
  const cv::Mat& ta = a.materials[0].texture;
  ASSERT_EQ(ta.type(), CV_32FC3);
  EXPECT_EQ(cv::norm(ta, b.materials[0].texture, cv::NORM_INF), 0.0);
  // Gradients everywhere: every 64x64 tile has texture.
  for (int y = 0; y + 64 <= ta.rows; y += 64) {
    for (int x = 0; x + 64 <= ta.cols; x += 64) {
      EXPECT_GT(MeanGradient(ta(cv::Rect(x, y, 64, 64))), 0.01) << x << "," << y;
    }
  }
}

TEST(TexturedSphere, UsesGivenTexture) {
  cv::Mat tex(10, 20, CV_8UC3, cv::Scalar(255, 0, 0));
  const Mesh sphere = MakeTexturedSphere(0.03, 4, 8, tex);
  ASSERT_EQ(sphere.materials[0].texture.type(), CV_32FC3);
  EXPECT_EQ(sphere.materials[0].texture.size(), tex.size());
  EXPECT_FLOAT_EQ(sphere.materials[0].texture.at<cv::Vec3f>(5, 5)[0], 1.0f);
  EXPECT_THROW(MakeTexturedSphere(0.0), Error);
  EXPECT_THROW(MakeTexturedSphere(0.1, 1, 8), Error);
  EXPECT_THROW(MakeTexturedSphere(0.1, 4, 2), Error);
}

TEST(TexturedBox, GeometryOrientationAndTextures) {
  const Mesh box = MakeTexturedBox({0.16, 0.10, 0.06});
  EXPECT_NO_THROW(box.Check("box"));
  EXPECT_EQ(box.num_triangles(), 12);
  Eigen::Vector3f lo, hi;
  box.BoundingBox(&lo, &hi);
  EXPECT_TRUE(hi.isApprox(Eigen::Vector3f(0.08f, 0.05f, 0.03f)));
  EXPECT_TRUE(lo.isApprox(Eigen::Vector3f(-0.08f, -0.05f, -0.03f)));
  ExpectOutwardTriangles(box);
  ExpectTexturesNotMirrored(box);
  ASSERT_EQ(box.materials.size(), 6u);
  // +x face spans y (0.10) by z (0.06): texture keeps that aspect ratio.
  EXPECT_EQ(box.materials[0].texture.cols, 256);
  EXPECT_NEAR(box.materials[0].texture.rows, 256 * 0.6, 1);
  for (int a = 0; a < 6; ++a) {
    EXPECT_GT(MeanGradient(box.materials[a].texture), 0.05) << box.materials[a].name;
    for (int b = a + 1; b < 6; ++b) {
      cv::Mat ra, rb;
      cv::resize(box.materials[a].texture, ra, {64, 64});
      cv::resize(box.materials[b].texture, rb, {64, 64});
      EXPECT_GT(cv::norm(ra, rb, cv::NORM_L1) / (64 * 64 * 3), 0.05) << a << " vs " << b;
    }
  }
}

TEST(TexturedBox, UsesGivenTexturesAndRejectsBadSize) {
  std::array<cv::Mat, 6> textures;
  textures[3] = cv::Mat(8, 8, CV_8UC1, cv::Scalar(128));
  const Mesh box = MakeTexturedBox({1, 1, 1}, textures);
  EXPECT_EQ(box.materials[3].texture.size(), cv::Size(8, 8));
  EXPECT_EQ(box.materials[3].texture.type(), CV_32FC3);
  EXPECT_THROW(MakeTexturedBox({0, 1, 1}), Error);
  EXPECT_THROW(MakeTexturedBox({1, std::nan(""), 1}), Error);
}

}  // namespace
}  // namespace unseen
