// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/render/shading.h"

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "unseen/util/error.h"
#include "unseen/util/testing.h"

namespace unseen {
namespace {

PinholeCamera TestCamera() { return PinholeCamera::Centered(160, 120, 100.0); }

// A camera-facing square (normal -z) of half-size h centred on (x, y, z), appended to
// `mesh` with material `material`.
void AddFacingSquare(Mesh* mesh, double x, double y, double z, double h, int material) {
  const int base = mesh->num_vertices();
  const float fx = float(x), fy = float(y), fz = float(z), fh = float(h);
  // Top-left, bottom-left, bottom-right, top-right (counter-clockwise seen from -z).
  mesh->vertices.insert(mesh->vertices.end(), {{fx - fh, fy - fh, fz},
                                               {fx - fh, fy + fh, fz},
                                               {fx + fh, fy + fh, fz},
                                               {fx + fh, fy - fh, fz}});
  mesh->triangles.emplace_back(base, base + 1, base + 2);
  mesh->triangles.emplace_back(base, base + 2, base + 3);
  mesh->triangle_materials.push_back(material);
  mesh->triangle_materials.push_back(material);
}

Mesh OneSquare(const Eigen::Vector3f& albedo) {
  Mesh m;
  Material material;
  material.diffuse_bgr = albedo;
  m.materials = {material};
  AddFacingSquare(&m, 0.0, 0.0, 1.0, 0.5, 0);
  return m;
}

cv::Vec3f ExpectedColor(const Eigen::Vector3f& albedo, const Eigen::Vector3d& light) {
  cv::Vec3f c;
  for (int k = 0; k < 3; ++k) c[k] = float(std::min(1.0, albedo[k] * light[k]));
  return c;
}

void ExpectColorNear(const cv::Vec3f& got, const cv::Vec3f& want, double tolerance,
                     const std::string& where) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], want[k], tolerance) << where << " channel " << k;
}

TEST(Shading, DirectionalLightFollowsLambertsCosine) {
  const PinholeCamera cam = TestCamera();
  const Eigen::Vector3f albedo(0.8f, 0.6f, 0.4f);
  const Mesh square = OneSquare(albedo);
  Lighting lighting;
  lighting.ambient_bgr = Eigen::Vector3f::Constant(0.1f);
  DirectionalLight light;
  light.intensity = 0.5;
  light.color_bgr = Eigen::Vector3f(1.0f, 0.5f, 1.0f);
  const Eigen::Vector3d light_bgr = light.color_bgr.cast<double>();
  RenderBuffers out;
  struct Case {
    Eigen::Vector3d direction;
    double cosine;
  };
  const double s60 = std::sin(M_PI / 3), c60 = std::cos(M_PI / 3);
  for (const Case& c : {Case{{0, 0, 1}, 1.0}, Case{{s60, 0, c60}, 0.5},
                        Case{{0, -s60, c60}, 0.5}, Case{{0, 0, -1}, 0.0}}) {
    light.direction_in_cam = c.direction;
    lighting.directional = {light};
    RenderShaded(square, cam, Rigid3d(), cam.ImageRect(), lighting, RenderOptions(),
                 ShadingOptions(), &out);
    const Eigen::Vector3d expected = Eigen::Vector3d::Constant(0.1) + 0.5 * c.cosine * light_bgr;
    ExpectColorNear(out.color.at<cv::Vec3f>(60, 80), ExpectedColor(albedo, expected), 1e-5,
                    "cosine " + std::to_string(c.cosine));
    ExpectColorNear(out.color.at<cv::Vec3f>(30, 40), ExpectedColor(albedo, expected), 1e-5,
                    "cosine " + std::to_string(c.cosine));
  }
  EXPECT_EQ(out.color.at<cv::Vec3f>(2, 2), cv::Vec3f(0, 0, 0));  // background stays empty
}

TEST(Shading, PointLightFallsOffWithTheSquaredDistance) {
  const PinholeCamera cam = TestCamera();
  const Eigen::Vector3f albedo(0.5f, 0.7f, 0.9f);
  const Mesh square = OneSquare(albedo);
  Lighting lighting;
  lighting.ambient_bgr = Eigen::Vector3f(0.05f, 0.1f, 0.0f);
  PointLight light;
  light.position_in_cam = Eigen::Vector3d(0.1, -0.05, 0.5);
  light.intensity = 0.2;
  lighting.point = {light};
  RenderBuffers out;
  RenderShaded(square, cam, Rigid3d(), cam.ImageRect(), lighting, RenderOptions(),
               ShadingOptions(), &out);
  for (const auto& [u, v] : std::vector<std::pair<int, int>>{{80, 60}, {50, 30}, {110, 90}}) {
    const Eigen::Vector3d p = cam.Unproject(Eigen::Vector2d(u, v), 1.0);
    const Eigen::Vector3d to_light = light.position_in_cam - p;
    const double cosine = Eigen::Vector3d(0, 0, -1).dot(to_light.normalized());
    const Eigen::Vector3d expected =
        lighting.ambient_bgr.cast<double>() +
        Eigen::Vector3d::Constant(light.intensity * cosine / to_light.squaredNorm());
    ExpectColorNear(out.color.at<cv::Vec3f>(v, u), ExpectedColor(albedo, expected), 1e-5,
                    std::to_string(u) + "," + std::to_string(v));
  }
}

// An occluder square in front of a wall: the light's shadow falls where geometry says.
class ShadowTest : public ::testing::Test {
 protected:
  void SetUp() override {
    Material white;
    white.diffuse_bgr = Eigen::Vector3f::Ones();
    scene_.materials = {white};
    AddFacingSquare(&scene_, 0.0, 0.0, 2.0, 0.6, 0);   // wall
    AddFacingSquare(&scene_, 0.0, 0.0, 1.5, 0.1, 0);   // occluder
    lighting_.ambient_bgr = Eigen::Vector3f::Constant(0.2f);
  }

  // Colour at the image point of camera-frame point p.
  cv::Vec3f ColorAt(const Eigen::Vector3d& p) const {
    const Eigen::Vector2d q = cam_.Project(p);
    return out_.color.at<cv::Vec3f>(int(std::lround(q.y())), int(std::lround(q.x())));
  }

  void Render() {
    RenderShaded(scene_, cam_, Rigid3d(), cam_.ImageRect(), lighting_, RenderOptions(),
                 ShadingOptions(), &out_);
  }

  // Pixels of the wall away from the shadow and the occluder outline must be fully lit.
  void ExpectWallLitOutside(const std::function<bool(const Eigen::Vector3d&)>& near_shadow,
                            float lit) {
    int checked = 0;
    for (int v = 0; v < cam_.height; ++v) {
      for (int u = 0; u < cam_.width; ++u) {
        if (std::abs(out_.depth.at<float>(v, u) - 2.0f) > 1e-4f) continue;  // not the wall
        const Eigen::Vector3d p = cam_.Unproject(Eigen::Vector2d(u, v), 2.0);
        if (near_shadow(p)) continue;
        ++checked;
        ASSERT_NEAR(out_.color.at<cv::Vec3f>(v, u)[0], lit, 1e-4) << u << " " << v;
      }
    }
    EXPECT_GT(checked, 2000);
  }

  PinholeCamera cam_ = TestCamera();
  Mesh scene_;
  Lighting lighting_;
  RenderBuffers out_;
};

TEST_F(ShadowTest, DirectionalLightCastsTheOccludersShadow) {
  DirectionalLight light;
  light.direction_in_cam = Eigen::Vector3d(0.6, 0.0, 1.0);
  light.intensity = 0.5;
  light.cast_shadows = true;
  lighting_.directional = {light};
  Render();
  const Eigen::Vector3d d = light.direction_in_cam.normalized();
  const double cosine = d.z();
  const float lit = float(0.2 + 0.5 * cosine);
  // Shadow of the occluder's centre (0, 0, 1.5) on the wall z = 2.
  const Eigen::Vector3d shadow = Eigen::Vector3d(0, 0, 1.5) + (0.5 / d.z()) * d;
  EXPECT_NEAR(ColorAt(shadow)[0], 0.2f, 1e-5);
  EXPECT_NEAR(ColorAt(shadow + Eigen::Vector3d(0.05, 0.05, 0))[0], 0.2f, 1e-5);
  EXPECT_NEAR(ColorAt(Eigen::Vector3d(-0.4, 0.0, 2.0))[0], lit, 1e-5);
  EXPECT_NEAR(ColorAt(Eigen::Vector3d(0.0, 0.0, 1.5))[0], lit, 1e-5);  // occluder: no acne
  ExpectWallLitOutside(
      [&](const Eigen::Vector3d& p) {
        return (p - shadow).cwiseAbs().maxCoeff() < 0.1 + 0.03 ||
               (p.head<2>() / 2.0).cwiseAbs().maxCoeff() < 0.1 / 1.5 + 0.01;
      },
      lit);

  lighting_.directional[0].cast_shadows = false;
  Render();
  EXPECT_NEAR(ColorAt(shadow)[0], lit, 1e-5);
}

TEST_F(ShadowTest, PointLightCastsTheOccludersShadow) {
  PointLight light;
  light.position_in_cam = Eigen::Vector3d(-0.6, 0.0, 0.0);
  light.intensity = 2.0;
  light.cast_shadows = true;
  lighting_.point = {light};
  Render();
  // Shadow of the occluder's centre on the wall: L + t (c - L) with z = 2.
  const Eigen::Vector3d c(0, 0, 1.5);
  const Eigen::Vector3d shadow = light.position_in_cam + (2.0 / 1.5) * (c - light.position_in_cam);
  EXPECT_NEAR(ColorAt(shadow)[0], 0.2f, 1e-5);
  const Eigen::Vector3d lit_point(-0.39, 0.21, 2.0);  // the centre of pixel (60, 70)
  const Eigen::Vector3d to_light = light.position_in_cam - lit_point;
  const double lit = 0.2 + 2.0 * (-to_light.normalized().z()) / to_light.squaredNorm();
  ASSERT_GT(lit, 0.3);
  EXPECT_NEAR(ColorAt(lit_point)[0], lit, 1e-5);

  lighting_.point[0].cast_shadows = false;
  Render();
  EXPECT_GT(ColorAt(shadow)[0], 0.3f);
}

TEST(Shading, BackFacesAreLitWithFlippedNormalsWhenTwoSided) {
  const PinholeCamera cam = TestCamera();
  Mesh square = OneSquare(Eigen::Vector3f::Ones());
  for (Eigen::Vector3i& t : square.triangles) std::swap(t[1], t[2]);  // now faces +z, away
  Lighting lighting;
  lighting.ambient_bgr = Eigen::Vector3f::Constant(0.25f);
  DirectionalLight light;
  light.direction_in_cam = Eigen::Vector3d(0, 0, 1);
  light.intensity = 0.5;
  lighting.directional = {light};
  RenderOptions options;
  options.cull_back_faces = false;
  ShadingOptions shading;
  RenderBuffers out;
  RenderShaded(square, cam, Rigid3d(), cam.ImageRect(), lighting, options, shading, &out);
  EXPECT_NEAR(out.color.at<cv::Vec3f>(60, 80)[1], 0.75f, 1e-5);
  EXPECT_NEAR(out.normal.at<cv::Vec3f>(60, 80)[2], -1.0f, 1e-5);
  shading.two_sided = false;
  RenderShaded(square, cam, Rigid3d(), cam.ImageRect(), lighting, options, shading, &out);
  EXPECT_NEAR(out.color.at<cv::Vec3f>(60, 80)[1], 0.25f, 1e-5);
}

TEST(Shading, ColourIsClampedToOne) {
  const PinholeCamera cam = TestCamera();
  const Mesh square = OneSquare(Eigen::Vector3f(0.5f, 0.5f, 0.5f));
  Lighting lighting;
  DirectionalLight light;
  light.intensity = 10.0;
  lighting.directional = {light};
  RenderBuffers out;
  RenderShaded(square, cam, Rigid3d(), cam.ImageRect(), lighting, RenderOptions(),
               ShadingOptions(), &out);
  EXPECT_EQ(out.color.at<cv::Vec3f>(60, 80), cv::Vec3f(1, 1, 1));
}

TEST(Shading, BadInputThrows) {
  const PinholeCamera cam = TestCamera();
  const Mesh square = OneSquare(Eigen::Vector3f::Ones());
  RenderBuffers out;
  auto shade = [&](Lighting lighting, ShadingOptions shading) {
    return [&, lighting, shading] {
      RenderShaded(square, cam, Rigid3d(), cam.ImageRect(), lighting, RenderOptions(), shading,
                   &out);
    };
  };
  Lighting lighting;
  lighting.directional.resize(2);
  lighting.point.resize(1);
  EXPECT_NO_THROW(shade(lighting, ShadingOptions())());

  Lighting bad = lighting;
  bad.directional[1].direction_in_cam.setZero();
  testing::ExpectError(shade(bad, ShadingOptions()), {"directional[1].direction_in_cam"});
  bad = lighting;
  bad.point[0].intensity = -1;
  testing::ExpectError(shade(bad, ShadingOptions()), {"point[0].intensity"});
  bad = lighting;
  bad.point[0].position_in_cam.x() = std::nan("");
  testing::ExpectError(shade(bad, ShadingOptions()), {"point[0].position_in_cam"});
  bad = lighting;
  bad.ambient_bgr.y() = -0.1f;
  testing::ExpectError(shade(bad, ShadingOptions()), {"ambient_bgr"});
  ShadingOptions bad_options;
  bad_options.shadow_map_px = 4;
  testing::ExpectError(shade(lighting, bad_options), {"shadow_map_px"});
  bad_options = ShadingOptions();
  bad_options.shadow_bias_m = -1;
  testing::ExpectError(shade(lighting, bad_options), {"shadow_bias_m"});
  PinholeCamera bad_cam = cam;
  bad_cam.fy = -1;
  testing::ExpectError(
      [&] {
        RenderShaded(square, bad_cam, Rigid3d(), cam.ImageRect(), lighting, RenderOptions(),
                     ShadingOptions(), &out);
      },
      {"fy=-1"});
}

}  // namespace
}  // namespace unseen
