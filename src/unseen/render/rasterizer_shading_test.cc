// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The rasterizer's colour: UV textures and their mip-map levels, vertex colours, projective
// textures, and the shading of whole 2x2 blocks.
#include "unseen/render/rasterizer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "unseen/render/mipmap.h"
#include "unseen/render/test_render_meshes.h"
#include "unseen/util/thread_pool.h"

namespace unseen {
namespace {

using render_testing::MakeQuad;
using render_testing::MakeScreenQuad;
using render_testing::MakeTiltedQuad;
using render_testing::MakeSphere;
using render_testing::PlaneDepth;
using render_testing::Pose;
using render_testing::RandomTexture;
using render_testing::TestCamera;

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
  Mesh quad = MakeTiltedQuad();
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
  Mesh quad = MakeTiltedQuad();
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

}  // namespace
}  // namespace unseen
