// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/render/rasterizer.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "unseen/render/mipmap.h"
#include "unseen/util/error.h"
#include "unseen/util/testing.h"
#include "unseen/util/thread_pool.h"

namespace unseen {
namespace {

PinholeCamera TestCamera(int width = 160, int height = 120) {
  PinholeCamera c;
  c.width = width;
  c.height = height;
  c.fx = 100.0;
  c.fy = 110.0;
  c.cx = (width - 1) / 2.0 + 0.25;
  c.cy = (height - 1) / 2.0 - 0.3;
  return c;
}

// A quad p0 p1 p2 p3 (counter-clockwise seen from the side it faces) as two triangles.
Mesh MakeQuad(const std::vector<Eigen::Vector3f>& corners) {
  Mesh m;
  m.vertices = corners;
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

// A camera-facing quad at depth z covering pixel rectangle [u0, u1] x [v0, v1] (pixels).
// Seen from the camera, counter-clockwise with y down means: top-left, bottom-left,
// bottom-right, top-right.
Mesh MakeScreenQuad(const PinholeCamera& cam, double u0, double v0, double u1, double v1,
                    double z) {
  auto at = [&](double u, double v) {
    return cam.Unproject(Eigen::Vector2d(u, v), z).cast<float>().eval();
  };
  return MakeQuad({at(u0, v0), at(u0, v1), at(u1, v1), at(u1, v0)});
}

// Axis-aligned cube centred on the origin, triangles counter-clockwise seen from outside.
Mesh MakeCube(float edge) {
  Mesh m;
  const float h = edge / 2;
  for (int i = 0; i < 8; ++i) {
    m.vertices.emplace_back(i & 1 ? h : -h, i & 2 ? h : -h, i & 4 ? h : -h);
  }
  // Faces as quads of corner indices, counter-clockwise seen from outside.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.emplace_back(q[0], q[1], q[2]);
    m.triangles.emplace_back(q[0], q[2], q[3]);
  }
  return m;
}

// UV sphere with vertex colours that vary over the surface.
Mesh MakeSphere(float radius, int rings, int segments) {
  Mesh m;
  for (int r = 0; r <= rings; ++r) {
    const double theta = M_PI * r / rings;
    for (int s = 0; s <= segments; ++s) {
      const double phi = 2 * M_PI * s / segments;
      const Eigen::Vector3f n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                              std::cos(theta));
      m.vertices.push_back(radius * n);
      m.normals.push_back(n);
      m.colors_bgr.emplace_back(0.5f + 0.5f * n.x(), 0.5f + 0.5f * n.y(), 0.5f + 0.5f * n.z());
      m.uvs.emplace_back(float(s) / segments, 1.0f - float(r) / rings);
    }
  }
  const int row = segments + 1;
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      const int a = r * row + s, b = a + 1, c = a + row, d = c + 1;
      // Outward: theta grows downward from the +z pole, phi counter-clockwise about +z.
      if (r > 0) m.triangles.emplace_back(a, c, b);
      if (r + 1 < rings) m.triangles.emplace_back(b, c, d);
    }
  }
  return m;
}

Rigid3d Pose(const Eigen::Vector3d& rotation_vector, const Eigen::Vector3d& t) {
  return Rigid3d(ExpSO3(rotation_vector), t);
}

cv::Mat RandomTexture(int w, int h, unsigned seed) {
  cv::Mat t(h, w, CV_32FC3);
  cv::RNG rng(seed);
  rng.fill(t, cv::RNG::UNIFORM, 0.0, 1.0);
  return t;
}

// Ray-plane depth at pixel (u, v) for the plane n . p = d (camera frame).
double PlaneDepth(const PinholeCamera& cam, double u, double v, const Eigen::Vector3d& n,
                  double d) {
  const Eigen::Vector3d ray((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
  return d / n.dot(ray);
}

// Float rounding plus the effect of snapping vertices to 1/256 px: the depth gradient
// times 1/256 px.
double DepthTolerance(const PinholeCamera& cam, double u, double v, const Eigen::Vector3d& n,
                      double d) {
  const double z = PlaneDepth(cam, u, v, n, d);
  const double gradient = std::abs(PlaneDepth(cam, u + 1, v, n, d) - z) +
                          std::abs(PlaneDepth(cam, u, v + 1, n, d) - z);
  return 1e-6 * z + gradient / 256.0;
}

TEST(Rasterizer, FrontoParallelPlaneHasExactDepthAndCoverage) {
  const PinholeCamera cam = TestCamera();
  const double z = 1.7;
  const Mesh quad = MakeScreenQuad(cam, 20.3, 10.6, 130.7, 95.2, z);
  RenderBuffers out;
  Render(quad, cam, Rigid3d(), cam.ImageRect(), RenderOptions(), &out);
  ASSERT_EQ(out.depth.size(), cv::Size(cam.width, cam.height));
  int covered = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const bool inside = u >= 21 && u <= 130 && v >= 11 && v <= 95;
      ASSERT_EQ(out.mask.at<uint8_t>(v, u), inside ? 255 : 0) << u << " " << v;
      if (inside) {
        ASSERT_NEAR(out.depth.at<float>(v, u), z, 1e-6 * z);
        ++covered;
      } else {
        ASSERT_EQ(out.depth.at<float>(v, u), 0.0f);
      }
    }
  }
  EXPECT_EQ(covered, 110 * 85);
  // No texture, no vertex colour, no material: white.
  EXPECT_EQ(out.color.at<cv::Vec3f>(50, 50), cv::Vec3f(1, 1, 1));
  EXPECT_EQ(out.color.at<cv::Vec3f>(5, 5), cv::Vec3f(0, 0, 0));
}

TEST(Rasterizer, TriangleIdsNameTheVisibleTriangle) {
  const PinholeCamera cam = TestCamera();
  // Triangle 0 = (top-left, bottom-left, bottom-right), 1 = (top-left, bottom-right,
  // top-right).
  const Mesh quad = MakeScreenQuad(cam, 20.5, 10.5, 120.5, 110.5, 1.0);
  RenderOptions options;
  options.write_triangle_ids = true;
  RenderBuffers out;
  Render(quad, cam, Rigid3d(), cam.ImageRect(), options, &out);
  ASSERT_EQ(out.triangle_id.type(), CV_32SC1);
  EXPECT_EQ(out.triangle_id.at<int>(100, 30), 0);  // bottom-left
  EXPECT_EQ(out.triangle_id.at<int>(20, 110), 1);  // top-right
  EXPECT_EQ(out.triangle_id.at<int>(5, 5), -1);
  EXPECT_EQ(cv::countNonZero(out.triangle_id >= 0), 100 * 100);
}

TEST(Rasterizer, HugeTrianglesAreClippedToTheGuardBand) {
  const PinholeCamera cam = TestCamera();
  // Corners thousands of metres off-axis project far beyond the fixed-point range.
  const float h = 5000.0f, z = 2.0f;
  const Mesh quad = MakeQuad({{-h, -h, z}, {-h, h, z}, {h, h, z}, {h, -h, z}});
  RenderBuffers out;
  Render(quad, cam, Rigid3d(), cam.ImageRect(), RenderOptions(), &out);
  EXPECT_EQ(cv::countNonZero(out.mask), cam.width * cam.height);
  double lo, hi;
  cv::minMaxLoc(out.depth, &lo, &hi);
  EXPECT_NEAR(lo, z, 1e-6 * z);
  EXPECT_NEAR(hi, z, 1e-6 * z);
}

TEST(Rasterizer, NonFiniteTextureCoordinatesGiveFiniteColours) {
  const PinholeCamera cam = TestCamera();
  Mesh quad = MakeScreenQuad(cam, 9.5, 9.5, 29.5, 29.5, 1.0);
  const float nan = std::nanf("");
  quad.uvs = {{nan, 1}, {0, nan}, {1e30f, 0}, {1, -1e30f}};
  Material material;
  material.texture = RandomTexture(8, 8, 1);
  quad.materials = {material};
  RenderBuffers out;
  Render(quad, cam, Rigid3d(), cam.ImageRect(), RenderOptions(), &out);
  EXPECT_EQ(cv::countNonZero(out.mask), 400);
  EXPECT_TRUE(cv::checkRange(out.color, true, nullptr, 0.0, 1.0));
}

TEST(Rasterizer, TiltedPlaneDepthMatchesRayIntersection) {
  const PinholeCamera cam = TestCamera();
  // A large quad in the plane through (0, 0, 2) with normal n, seen from the front.
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.4, -1.0).normalized();
  const Eigen::Vector3d centre(0.05, -0.02, 2.0);
  const Eigen::Vector3d e1 = n.cross(Eigen::Vector3d::UnitX()).normalized();
  const Eigen::Vector3d e2 = n.cross(e1);
  std::vector<Eigen::Vector3f> corners;
  for (const auto& [a, b] : std::vector<std::pair<double, double>>{{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
    corners.push_back((centre + 0.6 * (a * e1 + b * e2)).cast<float>());
  }
  Mesh quad = MakeQuad(corners);
  RenderOptions options;
  options.cull_back_faces = false;  // orientation is not the point here
  RenderBuffers out;
  Render(quad, cam, Rigid3d(), cam.ImageRect(), options, &out);
  const double d = n.dot(centre);
  int covered = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      if (!out.mask.at<uint8_t>(v, u)) continue;
      ++covered;
      const double expected = PlaneDepth(cam, u, v, n, d);
      ASSERT_NEAR(out.depth.at<float>(v, u), expected, DepthTolerance(cam, u, v, n, d))
          << u << " " << v;
    }
  }
  EXPECT_GT(covered, 1000);
}

TEST(Rasterizer, CubeSilhouetteMatchesProjectedCorners) {
  const PinholeCamera cam = TestCamera(200, 150);
  const Mesh cube = MakeCube(0.3f);
  for (int trial = 0; trial < 5; ++trial) {
    const Rigid3d pose = Pose(Eigen::Vector3d(0.4 + 0.3 * trial, -0.7 + 0.2 * trial, 0.2 * trial),
                              Eigen::Vector3d(0.03 * trial, -0.02, 1.2 + 0.1 * trial));
    RenderBuffers out;
    Render(cube, cam, pose, cam.ImageRect(), RenderOptions(), &out);
    std::vector<cv::Point2f> corners, hull;
    for (const Eigen::Vector3f& v : cube.vertices) {
      const Eigen::Vector2d q = cam.Project(pose * v.cast<double>());
      corners.emplace_back(float(q.x()), float(q.y()));
    }
    cv::convexHull(corners, hull);
    int checked = 0;
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        const double dist = cv::pointPolygonTest(hull, cv::Point2f(u, v), true);
        if (std::abs(dist) < 0.02) continue;  // on the outline: up to the fill rule
        ++checked;
        ASSERT_EQ(out.mask.at<uint8_t>(v, u) != 0, dist > 0) << trial << ": " << u << " " << v;
      }
    }
    EXPECT_GT(checked, cam.width * cam.height * 9 / 10);
  }
}

TEST(Rasterizer, TexturedQuadReproducesItsTexture) {
  const PinholeCamera cam = TestCamera();
  const int w = 64, h = 48, u0 = 30, v0 = 20;
  // Pixel edges at half-integers: pixel (u0 + i, v0 + j) centre is texel (i, j) centre.
  Mesh quad = MakeScreenQuad(cam, u0 - 0.5, v0 - 0.5, u0 + w - 0.5, v0 + h - 0.5, 1.3);
  quad.uvs = {{0, 1}, {0, 0}, {1, 0}, {1, 1}};  // v up: image row 0 is v = 1
  Material material;
  material.texture = RandomTexture(w, h, 7);
  quad.materials = {material};
  RenderBuffers out;
  Render(quad, cam, Rigid3d(), cam.ImageRect(), RenderOptions(), &out);
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      ASSERT_EQ(out.mask.at<uint8_t>(v0 + j, u0 + i), 255);
      const cv::Vec3f got = out.color.at<cv::Vec3f>(v0 + j, u0 + i);
      const cv::Vec3f want = material.texture.at<cv::Vec3f>(j, i);
      ASSERT_LT(cv::norm(got - want), 1e-4) << i << " " << j;
    }
  }
  EXPECT_EQ(cv::countNonZero(out.mask), w * h);
}

TEST(Rasterizer, TextureWrapsAndMaterialColourAppliesWithoutTexture) {
  const PinholeCamera cam = TestCamera();
  Mesh quad = MakeScreenQuad(cam, 9.5, 9.5, 29.5, 29.5, 1.0);
  // uv shifted by exactly one period: the same image as uv in [0, 1].
  quad.uvs = {{1, 2}, {1, 1}, {2, 1}, {2, 2}};
  Material textured;
  textured.texture = RandomTexture(20, 20, 3);
  Material plain;
  plain.diffuse_bgr = Eigen::Vector3f(0.1f, 0.2f, 0.3f);
  quad.materials = {textured, plain};
  quad.triangle_materials = {0, 0};
  RenderBuffers out;
  Render(quad, cam, Rigid3d(), cam.ImageRect(), RenderOptions(), &out);
  EXPECT_LT(cv::norm(out.color(cv::Rect(10, 10, 20, 20)), textured.texture, cv::NORM_INF), 1e-4);
  quad.triangle_materials = {1, 1};
  Render(quad, cam, Rigid3d(), cam.ImageRect(), RenderOptions(), &out);
  EXPECT_EQ(out.color.at<cv::Vec3f>(15, 15), cv::Vec3f(0.1f, 0.2f, 0.3f));
}

TEST(Rasterizer, SeveralTexturedMaterialsEachReproduceTheirTexture) {
  const PinholeCamera cam = TestCamera();
  Mesh quads = MakeScreenQuad(cam, 9.5, 9.5, 29.5, 29.5, 1.0);
  const Mesh second = MakeScreenQuad(cam, 49.5, 19.5, 79.5, 39.5, 1.2);
  quads.vertices.insert(quads.vertices.end(), second.vertices.begin(), second.vertices.end());
  quads.triangles.push_back({4, 5, 6});
  quads.triangles.push_back({4, 6, 7});
  quads.uvs = {{0, 1}, {0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}, {1, 0}, {1, 1}};
  Material a, b;
  a.texture = RandomTexture(20, 20, 5);
  b.texture = RandomTexture(30, 20, 6);
  quads.materials = {a, b};
  quads.triangle_materials = {0, 0, 1, 1};
  RenderBuffers out;
  Render(quads, cam, Rigid3d(), cam.ImageRect(), RenderOptions(), &out);
  EXPECT_LT(cv::norm(out.color(cv::Rect(10, 10, 20, 20)), a.texture, cv::NORM_INF), 1e-4);
  EXPECT_LT(cv::norm(out.color(cv::Rect(50, 20, 30, 20)), b.texture, cv::NORM_INF), 1e-4);
}

// Texture coordinates are interpolated directly when every material is textured and
// through barycentric coordinates otherwise (e.g. with normals); both must agree, also
// for triangles cut by the near plane.
TEST(Rasterizer, TextureCoordinatesAgreeBetweenInterpolationPaths) {
  const PinholeCamera cam = TestCamera(200, 160);
  Mesh sphere = MakeSphere(0.3f, 12, 24);
  Material material;
  material.texture = RandomTexture(64, 32, 9);
  cv::GaussianBlur(material.texture, material.texture, cv::Size(5, 5), 1.5);  // smooth
  sphere.materials = {material};
  sphere.colors_bgr.clear();
  RenderOptions uv_path, barycentric_path;
  barycentric_path.write_normals = true;
  // Far: no clipping; near: the sphere's front reaches z = 0.02 < near_m, so the near
  // plane cuts triangles.
  for (const Rigid3d& pose :
       {Pose(Eigen::Vector3d(0.4, 0.1, 0.2), Eigen::Vector3d(0, 0, 1.0)),
        Pose(Eigen::Vector3d(0.4, 0.1, 0.2), Eigen::Vector3d(0.03, 0.02, 0.32))}) {
    for (bool cull : {true, false}) {
      uv_path.cull_back_faces = barycentric_path.cull_back_faces = cull;
      uv_path.near_m = barycentric_path.near_m = 0.05;
      RenderBuffers a, b;
      Render(sphere, cam, pose, cam.ImageRect(), uv_path, &a);
      Render(sphere, cam, pose, cam.ImageRect(), barycentric_path, &b);
      EXPECT_EQ(cv::norm(a.mask, b.mask, cv::NORM_INF), 0.0);
      // (Near and culled: the whole visible front is nearer than near_m.)
      if (!cull || pose.translation().z() > 0.5) {
        EXPECT_GT(cv::countNonZero(a.mask), 1000);
      }
      EXPECT_LT(cv::norm(a.color, b.color, cv::NORM_INF), 1e-3);
    }
  }
}

TEST(Rasterizer, MinifiedTexturesAreSampledFromAMipmapLevel) {
  const PinholeCamera cam = TestCamera();
  // A 1-texel checkerboard of 256 x 256 texels on a 60 x 60 px quad: 18 texels per
  // pixel, level 2, where every texel is the mean 0.5. Without mip-maps it aliases.
  Mesh quad = MakeScreenQuad(cam, 19.5, 9.5, 79.5, 69.5, 1.0);
  quad.uvs = {{0, 1}, {0, 0}, {1, 0}, {1, 1}};
  Material material;
  material.texture.create(256, 256, CV_32FC3);
  for (int y = 0; y < 256; ++y) {
    for (int x = 0; x < 256; ++x) {
      material.texture.at<cv::Vec3f>(y, x) = cv::Vec3f::all((x + y) % 2 ? 1.0f : 0.0f);
    }
  }
  quad.materials = {material};
  RenderOptions options;
  RenderBuffers out;
  Render(quad, cam, Rigid3d(), cam.ImageRect(), options, &out);
  const cv::Mat inside = out.color(cv::Rect(20, 10, 60, 60));
  double lo, hi;
  cv::minMaxLoc(inside.reshape(1), &lo, &hi);
  EXPECT_NEAR(lo, 0.5, 1e-5);
  EXPECT_NEAR(hi, 0.5, 1e-5);
  options.mipmaps = false;
  Render(quad, cam, Rigid3d(), cam.ImageRect(), options, &out);
  cv::minMaxLoc(out.color(cv::Rect(20, 10, 60, 60)).reshape(1), &lo, &hi);
  EXPECT_GT(hi - lo, 0.5);

  // Preparing the model beforehand (its mip-maps built before the first render) renders
  // exactly the same.
  ClearMipmapCache();
  PrepareForRendering(quad);
  options.mipmaps = true;
  RenderBuffers prepared;
  Render(quad, cam, Rigid3d(), cam.ImageRect(), options, &prepared);
  ClearMipmapCache();
  Render(quad, cam, Rigid3d(), cam.ImageRect(), options, &out);
  EXPECT_EQ(cv::norm(prepared.color, out.color, cv::NORM_INF), 0.0);
  quad.materials.clear();
  PrepareForRendering(quad);  // nothing to prepare without a texture
}

// Fan and jittered grid covering [x0, x1] x [y0, y1]: every pixel centre strictly inside
// must be covered by exactly one triangle.
TEST(Rasterizer, SharedEdgesAreCoveredExactlyOnce) {
  const PinholeCamera cam = TestCamera(120, 100);
  const double x0 = 10.3, y0 = 8.7, x1 = 101.6, y1 = 90.4, z = 2.0;
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> jitter(-2.0, 2.0);
  std::uniform_int_distribution<int> coin(0, 2);
  Mesh grid;
  const int n = 9;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      double u = x0 + (x1 - x0) * i / n, v = y0 + (y1 - y0) * j / n;
      if (i > 0 && i < n && j > 0 && j < n) {
        if (coin(rng) == 0) {  // exactly on a pixel centre: the tie case
          u = std::round(u);
          v = std::round(v);
        } else {
          u += jitter(rng);
          v += jitter(rng);
        }
      }
      grid.vertices.push_back(cam.Unproject(Eigen::Vector2d(u, v), z).cast<float>());
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      // Camera-facing: counter-clockwise on screen (y down) is a, c, d, b.
      if ((i + j) % 2) {
        grid.triangles.emplace_back(a, c, d);
        grid.triangles.emplace_back(a, d, b);
      } else {
        grid.triangles.emplace_back(a, c, b);
        grid.triangles.emplace_back(b, c, d);
      }
    }
  }
  // A fan around a centre vertex on a pixel centre, with spokes through pixel centres.
  Mesh fan;
  fan.vertices.push_back(cam.Unproject(Eigen::Vector2d(55, 49), z).cast<float>());
  const int spokes = 16;
  for (int k = 0; k < spokes; ++k) {
    const double a = -2 * M_PI * k / spokes;  // counter-clockwise on screen
    fan.vertices.push_back(
        cam.Unproject(Eigen::Vector2d(std::round(55 + 40 * std::cos(a)), std::round(49 + 40 * std::sin(a))), z)
            .cast<float>());
  }
  for (int k = 0; k < spokes; ++k) fan.triangles.emplace_back(0, 1 + k, 1 + (k + 1) % spokes);

  for (const Mesh* mesh : {&grid, &fan}) {
    cv::Mat count = cv::Mat::zeros(cam.height, cam.width, CV_32SC1);
    RenderOptions options;
    RenderBuffers out;
    for (int t = 0; t < mesh->num_triangles(); ++t) {
      Mesh one;
      one.vertices = mesh->vertices;
      one.triangles = {mesh->triangles[t]};
      Render(one, cam, Rigid3d(), cam.ImageRect(), options, &out);
      cv::Mat m;
      out.mask.convertTo(m, CV_32S, 1.0 / 255);
      count += m;
    }
    double max_count;
    cv::minMaxLoc(count, nullptr, &max_count);
    EXPECT_EQ(max_count, 1.0) << "double coverage";
    options.write_triangle_ids = true;
    Render(*mesh, cam, Rigid3d(), cam.ImageRect(), options, &out);
    EXPECT_EQ(cv::countNonZero(out.mask), cv::countNonZero(count));
    if (mesh == &grid) {
      for (int v = 0; v < cam.height; ++v) {
        for (int u = 0; u < cam.width; ++u) {
          const bool inside = u > x0 && u < x1 && v > y0 && v < y1;
          ASSERT_EQ(count.at<int>(v, u), inside ? 1 : 0) << u << " " << v;
          ASSERT_EQ(out.triangle_id.at<int>(v, u) >= 0, inside);
        }
      }
    } else {
      EXPECT_GT(cv::countNonZero(count), 4000);
    }
  }
}

TEST(Rasterizer, RoiRenderEqualsWindowOfFullRender) {
  const PinholeCamera cam = TestCamera(200, 160);
  const Mesh sphere = MakeSphere(0.2f, 12, 24);
  const Rigid3d pose = Pose(Eigen::Vector3d(0.3, 0.5, -0.2), Eigen::Vector3d(0.05, 0.02, 0.9));
  RenderOptions options;
  options.write_triangle_ids = true;
  options.write_normals = true;
  RenderBuffers full, part;
  Render(sphere, cam, pose, cam.ImageRect(), options, &full);
  const PixelRect roi{37, 21, 151, 133};
  Render(sphere, cam, pose, roi, options, &part);
  ASSERT_EQ(part.roi, roi);
  const cv::Rect window(roi.x0, roi.y0, roi.width(), roi.height());
  EXPECT_EQ(cv::norm(full.depth(window), part.depth, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(full.mask(window), part.mask, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(full.color(window), part.color, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(full.normal(window), part.normal, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(full.triangle_id(window), part.triangle_id, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::countNonZero(part.mask), 1000);

  // A roi reaching outside the image is clipped to it.
  Render(sphere, cam, pose, PixelRect{-10, 100, 50, 400}, options, &part);
  EXPECT_EQ(part.roi, (PixelRect{0, 100, 50, 160}));
  EXPECT_EQ(part.depth.size(), cv::Size(50, 60));
  // An empty roi gives empty buffers.
  Render(sphere, cam, pose, PixelRect{300, 0, 400, 10}, options, &part);
  EXPECT_TRUE(part.roi.empty());
  EXPECT_TRUE(part.depth.empty());
  EXPECT_TRUE(part.mask.empty());
  EXPECT_TRUE(part.color.empty());
}

TEST(Rasterizer, DepthOnlyMatchesColourRenderAndBuffersAreReused) {
  const PinholeCamera cam = TestCamera(200, 160);
  const Mesh sphere = MakeSphere(0.2f, 10, 20);
  const Rigid3d pose = Pose(Eigen::Vector3d(0.1, 0.2, 0.3), Eigen::Vector3d(0.0, 0.0, 1.0));
  RenderBuffers a, b;
  Render(sphere, cam, pose, cam.ImageRect(), RenderOptions(), &a);
  RenderOptions depth_only;
  depth_only.write_color = false;
  Render(sphere, cam, pose, cam.ImageRect(), depth_only, &b);
  EXPECT_EQ(cv::norm(a.depth, b.depth, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a.mask, b.mask, cv::NORM_INF), 0.0);
  EXPECT_TRUE(b.color.empty());
  EXPECT_TRUE(b.triangle_id.empty());
  const float* depth_data = a.depth.ptr<float>();
  const float* color_data = a.color.ptr<float>();
  Render(sphere, cam, pose * Pose(Eigen::Vector3d(0, 0.1, 0), Eigen::Vector3d::Zero()),
         cam.ImageRect(), RenderOptions(), &a);
  EXPECT_EQ(a.depth.ptr<float>(), depth_data);
  EXPECT_EQ(a.color.ptr<float>(), color_data);
}

TEST(Rasterizer, BackFaceCulling) {
  const PinholeCamera cam = TestCamera();
  // Left quad faces the camera, right quad faces away (reversed winding).
  Mesh front = MakeScreenQuad(cam, 10.5, 10.5, 50.5, 50.5, 1.0);
  Mesh back = MakeScreenQuad(cam, 80.5, 10.5, 120.5, 50.5, 1.0);
  for (Eigen::Vector3i& t : back.triangles) std::swap(t[1], t[2]);
  Mesh both = front;
  for (const Eigen::Vector3i& t : back.triangles) both.triangles.push_back(t.array() + 4);
  both.vertices.insert(both.vertices.end(), back.vertices.begin(), back.vertices.end());
  RenderBuffers out;
  RenderOptions options;
  Render(both, cam, Rigid3d(), cam.ImageRect(), options, &out);
  EXPECT_EQ(out.mask.at<uint8_t>(30, 30), 255);
  EXPECT_EQ(out.mask.at<uint8_t>(30, 100), 0);
  EXPECT_EQ(cv::countNonZero(out.mask), 40 * 40);
  options.cull_back_faces = false;
  Render(both, cam, Rigid3d(), cam.ImageRect(), options, &out);
  EXPECT_EQ(out.mask.at<uint8_t>(30, 100), 255);
  EXPECT_EQ(cv::countNonZero(out.mask), 2 * 40 * 40);

  // A closed cube: without culling the nearest surface still wins.
  const Mesh cube = MakeCube(0.4f);
  const Rigid3d pose = Pose(Eigen::Vector3d(0.5, 0.6, 0.1), Eigen::Vector3d(0, 0, 1.5));
  RenderBuffers culled, unculled;
  Render(cube, cam, pose, cam.ImageRect(), RenderOptions(), &culled);
  Render(cube, cam, pose, cam.ImageRect(), options, &unculled);
  EXPECT_EQ(cv::norm(culled.mask, unculled.mask, cv::NORM_INF), 0.0);
  EXPECT_LT(cv::norm(culled.depth, unculled.depth, cv::NORM_INF), 1e-6);
  const Mesh sphere = MakeSphere(0.2f, 10, 20);
  Render(sphere, cam, pose, cam.ImageRect(), RenderOptions(), &culled);
  Render(sphere, cam, pose, cam.ImageRect(), options, &unculled);
  EXPECT_EQ(cv::norm(culled.mask, unculled.mask, cv::NORM_INF), 0.0);
  EXPECT_LT(cv::norm(culled.depth, unculled.depth, cv::NORM_INF), 1e-6);
}

TEST(Rasterizer, TriangleCrossingTheNearPlaneIsClipped) {
  const PinholeCamera cam = TestCamera();
  // A floor y = 0.3 from behind the camera (z = -2) to z = 6, x in [-3, 3], facing up
  // (normal -y, towards the camera which is above it).
  const float y = 0.3f;
  const Mesh floor = MakeQuad({{-3, y, -2}, {3, y, -2}, {3, y, 6}, {-3, y, 6}});
  const Eigen::Vector3d n(0, 1, 0);
  RenderOptions options;
  options.write_triangle_ids = true;
  for (double near : {0.05, 1.0}) {  // 1.0: the cut at z = near is in view
    for (bool cull : {true, false}) {
      options.near_m = near;
      options.cull_back_faces = cull;
      RenderBuffers out;
      Render(floor, cam, Rigid3d(), cam.ImageRect(), options, &out);
      int covered = 0;
      for (int v = 0; v < cam.height; ++v) {
        for (int u = 0; u < cam.width; ++u) {
          const double ray_y = (v - cam.cy) / cam.fy;
          bool expected = false;
          if (ray_y > 0) {
            const double z = y / ray_y, x = z * (u - cam.cx) / cam.fx;
            const bool inside = z > near + 0.005 && z < 6 - 0.1 && std::abs(x) < 3 - 0.02;
            const bool outside = z < near - 0.005 || z > 6 + 0.1 || std::abs(x) > 3 + 0.02;
            if (!inside && !outside) continue;  // on an outline: up to rounding
            expected = inside;
          }
          ASSERT_EQ(out.mask.at<uint8_t>(v, u) != 0, expected)
              << u << " " << v << " near " << near << " cull " << cull;
          if (expected) {
            ++covered;
            ASSERT_NEAR(out.depth.at<float>(v, u), PlaneDepth(cam, u, v, n, y),
                        DepthTolerance(cam, u, v, n, y));
            ASSERT_GE(out.depth.at<float>(v, u), near);
            ASSERT_GE(out.triangle_id.at<int>(v, u), 0);
            ASSERT_LE(out.triangle_id.at<int>(v, u), 1);
          }
        }
      }
      EXPECT_GT(covered, 1000);
    }
  }
  // Entirely behind the camera: nothing.
  const Mesh behind = MakeQuad({{-1, y, -3}, {1, y, -3}, {1, y, -1}, {-1, y, -1}});
  RenderBuffers out;
  Render(behind, cam, Rigid3d(), cam.ImageRect(), options, &out);
  EXPECT_EQ(cv::countNonZero(out.mask), 0);
}

TEST(Rasterizer, VertexColoursInterpolatePerspectiveCorrectly) {
  const PinholeCamera cam = TestCamera();
  // A strongly tilted triangle; colours affine in the 3-D position, so the correct
  // (perspective) interpolation reproduces that affine function exactly.
  Mesh tri;
  tri.vertices = {{-0.5f, -0.4f, 0.8f}, {0.1f, 0.5f, 1.2f}, {0.6f, -0.3f, 3.0f}};
  tri.triangles = {{0, 1, 2}};
  auto colour_of = [](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(0.5 + 0.5 * p.x(), 0.5 + 0.4 * p.y(), 0.25 * p.z() - 0.1);
  };
  for (const Eigen::Vector3f& v : tri.vertices) tri.colors_bgr.push_back(colour_of(v.cast<double>()).cast<float>());
  RenderOptions options;
  options.cull_back_faces = false;
  RenderBuffers out;
  Render(tri, cam, Rigid3d(), cam.ImageRect(), options, &out);
  const Eigen::Vector3d a = tri.vertices[0].cast<double>();
  const Eigen::Vector3d n =
      (tri.vertices[1].cast<double>() - a).cross(tri.vertices[2].cast<double>() - a).normalized();
  int covered = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      if (!out.mask.at<uint8_t>(v, u)) continue;
      ++covered;
      auto colour_at = [&](double pu, double pv) {
        return colour_of(cam.Unproject(Eigen::Vector2d(pu, pv), PlaneDepth(cam, pu, pv, n, n.dot(a))));
      };
      const Eigen::Vector3d want = colour_at(u, v);
      // Rounding plus snapping vertices to 1/256 px.
      const Eigen::Vector3d tolerance =
          1e-5 + ((colour_at(u + 1, v) - want).cwiseAbs() + (colour_at(u, v + 1) - want).cwiseAbs()).array() / 256.0;
      const cv::Vec3f got = out.color.at<cv::Vec3f>(v, u);
      for (int k = 0; k < 3; ++k) ASSERT_NEAR(got[k], want[k], tolerance[k]) << u << " " << v;
    }
  }
  EXPECT_GT(covered, 1000);
}

TEST(Rasterizer, ProjectiveTextureFromTheRenderingCameraReproducesTheImage) {
  const PinholeCamera cam = TestCamera();
  const Rigid3d cam_from_obj =
      Pose(Eigen::Vector3d(0.1, -0.2, 0.05), Eigen::Vector3d(0.02, 0.01, 1.0));
  // A tilted quad in the object frame, in view.
  Mesh quad = MakeQuad({{-0.3f, -0.25f, 0.1f}, {-0.3f, 0.25f, 0.0f}, {0.3f, 0.25f, -0.1f},
                        {0.3f, -0.25f, 0.0f}});
  Projector projector;
  projector.camera = cam;
  projector.cam_from_obj = cam_from_obj;
  projector.image = RandomTexture(cam.width, cam.height, 11);
  quad.projectors = {projector};
  RenderOptions options;
  options.cull_back_faces = false;
  RenderBuffers out;
  Render(quad, cam, cam_from_obj, cam.ImageRect(), options, &out);
  int covered = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      if (!out.mask.at<uint8_t>(v, u)) continue;
      ++covered;
      const cv::Vec3f got = out.color.at<cv::Vec3f>(v, u);
      ASSERT_LT(cv::norm(got - projector.image.at<cv::Vec3f>(v, u)), 0.012) << u << " " << v;
    }
  }
  EXPECT_GT(covered, 2000);

  // A projector that sees only the left half of the image: the rest falls back to the
  // material colour.
  quad.projectors[0].camera.width = cam.width / 2;
  quad.projectors[0].image = projector.image(cv::Rect(0, 0, cam.width / 2, cam.height)).clone();
  Material grey;
  grey.diffuse_bgr = Eigen::Vector3f::Constant(0.5f);
  quad.materials = {grey};
  Render(quad, cam, cam_from_obj, cam.ImageRect(), options, &out);
  int fallback = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      if (!out.mask.at<uint8_t>(v, u)) continue;
      const cv::Vec3f got = out.color.at<cv::Vec3f>(v, u);
      if (u <= cam.width / 2 - 2) {
        ASSERT_LT(cv::norm(got - projector.image.at<cv::Vec3f>(v, u)), 0.012) << u << " " << v;
      } else if (u >= cam.width / 2 + 1) {
        ASSERT_EQ(got, cv::Vec3f(0.5f, 0.5f, 0.5f)) << u << " " << v;
        ++fallback;
      }
    }
  }
  EXPECT_GT(fallback, 500);
}

TEST(Rasterizer, QuadShadingColoursEachWholeBlockOnceAndTheRestPerSample) {
  const PinholeCamera cam = TestCamera();
  const Rigid3d cam_from_obj =
      Pose(Eigen::Vector3d(0.3, -0.2, 0.05), Eigen::Vector3d(0.02, 0.01, 1.0));
  // Two tilted triangles, colours affine in the 3-D position.
  Mesh quad = MakeQuad({{-0.3f, -0.25f, 0.1f}, {-0.3f, 0.25f, 0.0f}, {0.3f, 0.25f, -0.1f},
                        {0.3f, -0.25f, 0.0f}});
  for (const Eigen::Vector3f& v : quad.vertices) {
    quad.colors_bgr.push_back(Eigen::Vector3f(0.5f + v.x(), 0.5f + v.y(), 0.5f + 2.0f * v.z()));
  }
  RenderOptions options;
  options.cull_back_faces = false;
  options.write_triangle_ids = true;
  RenderBuffers each, quads;
  Render(quad, cam, cam_from_obj, cam.ImageRect(), options, &each);
  options.shade_quads = true;
  Render(quad, cam, cam_from_obj, cam.ImageRect(), options, &quads);
  EXPECT_EQ(cv::countNonZero(each.mask != quads.mask), 0);
  EXPECT_EQ(cv::countNonZero(each.depth != quads.depth), 0);
  int whole = 0, partial = 0;
  for (int y = 0; y + 1 < cam.height; y += 2) {
    for (int x = 0; x + 1 < cam.width; x += 2) {
      const cv::Rect block(x, y, 2, 2);
      const cv::Mat ids = quads.triangle_id(block);
      const int id = ids.at<int32_t>(0, 0);
      if (id >= 0 && cv::countNonZero(ids == id) == 4) {
        // One shading for the block, at its centre: about the mean of its four samples.
        ++whole;
        const cv::Vec3f first = quads.color.at<cv::Vec3f>(y, x);
        cv::Vec3f mean(0.0f, 0.0f, 0.0f);
        for (int k = 0; k < 4; ++k) {
          ASSERT_EQ(quads.color.at<cv::Vec3f>(y + k / 2, x + k % 2), first) << x << " " << y;
          mean += 0.25f * each.color.at<cv::Vec3f>(y + k / 2, x + k % 2);
        }
        ASSERT_LT(cv::norm(first - mean), 1e-3) << x << " " << y;
      } else {
        // An edge crosses the block: each sample on its own, as without the option.
        if (cv::countNonZero(quads.mask(block)) > 0) ++partial;
        for (int k = 0; k < 4; ++k) {
          ASSERT_EQ(quads.color.at<cv::Vec3f>(y + k / 2, x + k % 2),
                    each.color.at<cv::Vec3f>(y + k / 2, x + k % 2))
              << x + k % 2 << " " << y + k / 2;
        }
      }
    }
  }
  EXPECT_GT(whole, 500);
  EXPECT_GT(partial, 20);

  // In bands of rows on three threads, with an odd number of rows: the same image.
  const PinholeCamera odd = TestCamera(160, 121);
  Render(quad, odd, cam_from_obj, odd.ImageRect(), options, &each);
  ThreadPool pool(3);
  options.pool = &pool;
  Render(quad, odd, cam_from_obj, odd.ImageRect(), options, &quads);
  EXPECT_EQ(cv::norm(each.color, quads.color, cv::NORM_INF), 0.0);
}

TEST(Rasterizer, QuadShadingOfAUvTextureSamplesTheBlocksMipmapLevel) {
  // A one-texel checkerboard at one texel per pixel: shaded per sample it is read from its
  // full-resolution level, each sample black, white or between as it falls; shaded once per
  // 2x2 block, a lookup stands for four pixels' texels and comes from the next level, where
  // the checker has averaged to grey, as the mean of the block's four samples about is.
  const PinholeCamera cam = TestCamera();
  const int side = 64;
  Mesh quad = MakeScreenQuad(cam, 40.5, 28.5, 40.5 + side, 28.5 + side, 1.0);
  quad.uvs = {{0, 1}, {0, 0}, {1, 0}, {1, 1}};
  Material material;
  material.texture.create(side, side, CV_32FC3);
  for (int y = 0; y < side; ++y) {
    for (int x = 0; x < side; ++x) {
      material.texture.at<cv::Vec3f>(y, x) = (x + y) % 2 ? cv::Vec3f(1, 1, 1) : cv::Vec3f(0, 0, 0);
    }
  }
  quad.materials = {material};
  // Turned in its plane so that samples fall anywhere between texel centres.
  const Eigen::Vector3d centre(0.0, 0.0, 1.0);
  const auto rotation = ExpSO3(Eigen::Vector3d(0.0, 0.0, 0.3));
  const Rigid3d turn(rotation, centre - rotation * centre);
  RenderOptions options;
  RenderBuffers each, quads;
  Render(quad, cam, turn, cam.ImageRect(), options, &each);
  options.shade_quads = true;
  Render(quad, cam, turn, cam.ImageRect(), options, &quads);
  EXPECT_EQ(cv::countNonZero(each.mask != quads.mask), 0);
  int whole = 0;
  double spread_each = 0.0;
  for (int y = 0; y + 1 < cam.height; y += 2) {
    for (int x = 0; x + 1 < cam.width; x += 2) {
      if (cv::countNonZero(quads.mask(cv::Rect(x, y, 2, 2))) < 4) continue;
      ++whole;
      const cv::Vec3f block = quads.color.at<cv::Vec3f>(y, x);
      for (int k = 0; k < 4; ++k) {
        ASSERT_EQ(quads.color.at<cv::Vec3f>(y + k / 2, x + k % 2), block) << x << " " << y;
        spread_each += std::abs(each.color.at<cv::Vec3f>(y + k / 2, x + k % 2)[0] - 0.5f);
      }
      ASSERT_NEAR(block[0], 0.5f, 0.02f) << x << " " << y;
    }
  }
  ASSERT_GT(whole, 500);
  EXPECT_GT(spread_each / (4.0 * whole), 0.1);  // the samples themselves are far from grey
}

TEST(Rasterizer, AProjectorsDepthHidesTheSurfaceBehindWhatItSaw) {
  // Two parallel quads, the near one covering the left half of the far one as the
  // projector sees them. Seen from the side, the far quad's hidden part must not take the
  // near quad's colours from the projector: it falls back to its material.
  const PinholeCamera cam = TestCamera();
  const Rigid3d projector_from_obj = Pose(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 1.0));
  Mesh scene = MakeQuad({{-0.3f, -0.3f, 0.2f}, {-0.3f, 0.3f, 0.2f}, {0.3f, 0.3f, 0.2f},
                         {0.3f, -0.3f, 0.2f}});
  const Mesh near = MakeQuad({{-0.5f, -0.5f, 0.0f}, {-0.5f, 0.5f, 0.0f}, {-0.05f, 0.5f, 0.0f},
                              {-0.05f, -0.5f, 0.0f}});
  const int offset = scene.num_vertices();
  for (const Eigen::Vector3f& v : near.vertices) scene.vertices.push_back(v);
  for (const Eigen::Vector3i& t : near.triangles) {
    scene.triangles.push_back(t + Eigen::Vector3i::Constant(offset));
  }
  scene.uvs.clear();
  Material grey;
  grey.diffuse_bgr = Eigen::Vector3f::Constant(0.5f);
  scene.materials = {grey};
  RenderOptions options;
  options.cull_back_faces = false;
  RenderBuffers seen;
  Render(scene, cam, projector_from_obj, cam.ImageRect(), options, &seen);
  Projector projector;
  projector.camera = cam;
  projector.cam_from_obj = projector_from_obj;
  projector.image = RandomTexture(cam.width, cam.height, 5);
  projector.depth = seen.depth.clone();
  // Only the far quad, seen from the projector's own place: its left half was hidden.
  Mesh far = MakeQuad({{-0.3f, -0.3f, 0.2f}, {-0.3f, 0.3f, 0.2f}, {0.3f, 0.3f, 0.2f},
                       {0.3f, -0.3f, 0.2f}});
  far.uvs.clear();
  far.materials = {grey};
  far.projectors = {projector};
  RenderBuffers out;
  Render(far, cam, projector_from_obj, cam.ImageRect(), options, &out);
  int hidden = 0, textured = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      if (!out.mask.at<uint8_t>(v, u)) continue;
      const cv::Vec3f got = out.color.at<cv::Vec3f>(v, u);
      const float near_z = seen.depth.at<float>(v, u);
      const float far_z = out.depth.at<float>(v, u);
      if (near_z < far_z - 0.05f) {  // the near quad is in front here
        ASSERT_EQ(got, cv::Vec3f(0.5f, 0.5f, 0.5f)) << u << " " << v;
        ++hidden;
      } else if (std::abs(near_z - far_z) < 1e-4f && u > 0 && v > 0 && u + 1 < cam.width &&
                 v + 1 < cam.height && seen.depth.at<float>(v, u - 1) > 0.15f &&
                 seen.depth.at<float>(v, u + 1) > 0.15f) {
        ASSERT_LT(cv::norm(got - projector.image.at<cv::Vec3f>(v, u)), 0.012) << u << " " << v;
        ++textured;
      }
    }
  }
  EXPECT_GT(hidden, 300);
  EXPECT_GT(textured, 300);
  // Without its depth, the projector paints the hidden half too.
  far.projectors[0].depth = cv::Mat();
  Render(far, cam, projector_from_obj, cam.ImageRect(), options, &out);
  int painted = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      if (out.mask.at<uint8_t>(v, u) && out.color.at<cv::Vec3f>(v, u) != cv::Vec3f(0.5f, 0.5f, 0.5f)) {
        ++painted;
      }
    }
  }
  EXPECT_GT(painted, hidden + textured);
}

TEST(Rasterizer, NormalsAreInTheCameraFrame) {
  const PinholeCamera cam = TestCamera();
  const Rigid3d pose = Pose(Eigen::Vector3d(0.0, 0.4, 0.0), Eigen::Vector3d(0, 0, 1.0));
  // Quad in the object's z = 0 plane facing -z (counter-clockwise seen from -z).
  Mesh quad = MakeQuad({{-0.2f, -0.2f, 0}, {-0.2f, 0.2f, 0}, {0.2f, 0.2f, 0}, {0.2f, -0.2f, 0}});
  RenderOptions options;
  options.write_normals = true;
  RenderBuffers out;
  Render(quad, cam, pose, cam.ImageRect(), options, &out);
  const Eigen::Vector3d want = pose.rotation() * Eigen::Vector3d(0, 0, -1);
  ASSERT_EQ(out.mask.at<uint8_t>(60, 80), 255);
  const cv::Vec3f got = out.normal.at<cv::Vec3f>(60, 80);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], want[k], 1e-5);
  EXPECT_EQ(out.normal.at<cv::Vec3f>(0, 0), cv::Vec3f(0, 0, 0));
}

TEST(Rasterizer, BadInputThrows) {
  const PinholeCamera cam = TestCamera();
  const Mesh good = MakeCube(0.2f);
  const Rigid3d pose(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 1));
  RenderBuffers out;
  auto render = [&](const Mesh& m, const PinholeCamera& c, const Rigid3d& p,
                    const RenderOptions& o) {
    return [&, m, c, p, o] { Render(m, c, p, c.ImageRect(), o, &out); };
  };
  const RenderOptions options;
  EXPECT_NO_THROW(render(good, cam, pose, options)());

  Mesh m = good;
  m.triangles.clear();
  testing::ExpectError(render(m, cam, pose, options), {"no triangles"});
  m = good;
  m.triangles[3][1] = 8;
  testing::ExpectError(render(m, cam, pose, options), {"triangle 3"});
  m = good;
  m.triangles[0][0] = -1;
  testing::ExpectError(render(m, cam, pose, options), {"triangle 0"});
  m = good;
  m.vertices[5].y() = std::nanf("");
  testing::ExpectError(render(m, cam, pose, options), {"vertex 5"});
  m = good;
  m.uvs.resize(3);
  testing::ExpectError(render(m, cam, pose, options), {"3 uvs"});
  m = good;
  m.colors_bgr.resize(9);
  testing::ExpectError(render(m, cam, pose, options), {"9 colours"});
  m = good;
  m.triangle_materials.assign(m.triangles.size(), 2);
  m.materials.resize(1);
  testing::ExpectError(render(m, cam, pose, options), {"material 2"});
  m = good;
  m.materials.resize(1);
  m.materials[0].texture = cv::Mat(4, 4, CV_8UC3);
  testing::ExpectError(render(m, cam, pose, options), {"CV_32FC3"});
  m = good;
  m.projectors.resize(1);
  testing::ExpectError(render(m, cam, pose, options), {"projector 0"});

  PinholeCamera bad_cam = cam;
  bad_cam.fx = 0;
  testing::ExpectError(render(good, bad_cam, pose, options), {"fx=0"});
  bad_cam = cam;
  bad_cam.width = -5;
  testing::ExpectError(render(good, bad_cam, pose, options), {"-5"});
  bad_cam = cam;
  bad_cam.width = 100000;
  testing::ExpectError(render(good, bad_cam, pose, options), {"100000"});

  RenderOptions bad_options;
  bad_options.near_m = 0;
  testing::ExpectError(render(good, cam, pose, bad_options), {"near_m"});
  Rigid3d bad_pose = pose;
  bad_pose.set_translation(Eigen::Vector3d(0, std::nan(""), 1));
  testing::ExpectError(render(good, cam, bad_pose, options), {"cam_from_obj"});
  EXPECT_THROW(Render(good, cam, pose, cam.ImageRect(), options, nullptr), Error);
}

}  // namespace
}  // namespace unseen
