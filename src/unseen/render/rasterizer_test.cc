// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/render/rasterizer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>
#include <utility>
#include <vector>

#include "unseen/render/test_render_meshes.h"
#include "unseen/util/error.h"
#include "unseen/util/testing.h"

namespace unseen {
namespace {

using render_testing::DepthTolerance;
using render_testing::MakeCube;
using render_testing::MakeQuad;
using render_testing::MakeScreenQuad;
using render_testing::MakeSphere;
using render_testing::PlaneDepth;
using render_testing::Pose;
using render_testing::RandomTexture;
using render_testing::TestCamera;

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
