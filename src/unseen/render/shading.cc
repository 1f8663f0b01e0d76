// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/render/shading.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "unseen/util/error.h"

namespace unseen {

namespace {

void CheckColor(const Eigen::Vector3f& c, const std::string& what) {
  UNSEEN_CHECK(c.allFinite() && (c.array() >= 0.0f).all(),
               "{} = ({} {} {}) must be finite and >= 0", what, c[0], c[1], c[2]);
}

void CheckIntensity(double i, const std::string& what) {
  UNSEEN_CHECK(std::isfinite(i) && i >= 0.0, "{} = {} must be finite and >= 0", what, i);
}

// Depth map of the mesh seen from a light, and how to look points up in it.
struct ShadowMap {
  PinholeCamera camera;
  Rigid3d light_from_cam;  // rendering camera frame -> light camera frame
  cv::Mat depth;           // CV_32FC1 z in the light frame, 0 where empty
};

// A square map of `size` px from `eye` (object frame) looking at the bounding sphere
// (centre, radius); std::nullopt when the eye is inside the sphere.
std::optional<ShadowMap> MakeShadowMap(const Mesh& mesh, const Eigen::Vector3d& eye,
                                       const Eigen::Vector3d& centre, double radius, int size,
                                       const Rigid3d& cam_from_obj) {
  Eigen::Vector3d z = centre - eye;
  const double distance = z.norm();
  if (!(distance > 1.01 * radius)) return std::nullopt;
  z /= distance;
  const Eigen::Vector3d helper =
      std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d x = (helper - helper.dot(z) * z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d light_from_obj_rotation;
  light_from_obj_rotation.row(0) = x;
  light_from_obj_rotation.row(1) = y;
  light_from_obj_rotation.row(2) = z;
  const Rigid3d light_from_obj = Rigid3d::FromRotationMatrix(
      light_from_obj_rotation, -light_from_obj_rotation * eye, "shadow map pose");

  ShadowMap map;
  map.camera.width = map.camera.height = size;
  const double half_angle = std::asin(radius / distance);
  map.camera.fx = map.camera.fy = (size / 2.0 - 1.0) / std::tan(half_angle);
  map.camera.cx = map.camera.cy = (size - 1) / 2.0;
  map.light_from_cam = light_from_obj * cam_from_obj.Inverse();
  RenderOptions options;
  options.cull_back_faces = false;
  options.write_color = false;
  options.near_m = std::max(1e-4, 0.5 * (distance - radius));
  RenderBuffers buffers;
  Render(mesh, map.camera, light_from_obj, map.camera.ImageRect(), options, &buffers);
  map.depth = buffers.depth;
  return map;
}

// Fraction in [0, 1] of the light reaching camera-frame point p (normal n, unit vector to
// the light l): the shadow test at the four texels around p's projection, bilinearly
// weighted (soft 1-texel edges).
double Visibility(const ShadowMap& map, const Eigen::Vector3d& p, const Eigen::Vector3d& n,
                  const Eigen::Vector3d& l, const ShadingOptions& shading) {
  const Eigen::Vector3d q = map.light_from_cam * p;
  if (!(q.z() > 0.0)) return 1.0;
  const double u = map.camera.fx * q.x() / q.z() + map.camera.cx;
  const double v = map.camera.fy * q.y() / q.z() + map.camera.cy;
  const double cos_angle = std::clamp(std::abs(n.dot(l)), 0.05, 1.0);
  const double tan_angle = std::sqrt(1.0 - cos_angle * cos_angle) / cos_angle;
  const double texel_m = q.z() / map.camera.fx;  // texel footprint at this depth
  const double bias = shading.shadow_bias_m + shading.shadow_slope_bias * texel_m * tan_angle;
  const double fu = std::floor(u), fv = std::floor(v);
  const double au = u - fu, av = v - fv;
  double visible = 0.0;
  for (int dv = 0; dv <= 1; ++dv) {
    for (int du = 0; du <= 1; ++du) {
      const double w = (du ? au : 1.0 - au) * (dv ? av : 1.0 - av);
      const int iu = static_cast<int>(fu) + du, iv = static_cast<int>(fv) + dv;
      bool lit = true;
      if (iu >= 0 && iv >= 0 && iu < map.camera.width && iv < map.camera.height) {
        const float d = map.depth.at<float>(iv, iu);
        lit = d == 0.0f || q.z() <= d + bias;
      }
      if (lit) visible += w;
    }
  }
  return visible;
}

}  // namespace

void Lighting::Check() const {
  CheckColor(ambient_bgr, "Lighting.ambient_bgr");
  for (size_t i = 0; i < directional.size(); ++i) {
    const DirectionalLight& l = directional[i];
    const std::string name = "Lighting.directional[" + std::to_string(i) + "]";
    UNSEEN_CHECK(l.direction_in_cam.allFinite() && l.direction_in_cam.norm() > 0.0,
                 "{}.direction_in_cam = ({} {} {}) must be finite and non-zero", name,
                 l.direction_in_cam.x(), l.direction_in_cam.y(), l.direction_in_cam.z());
    CheckColor(l.color_bgr, name + ".color_bgr");
    CheckIntensity(l.intensity, name + ".intensity");
  }
  for (size_t i = 0; i < point.size(); ++i) {
    const PointLight& l = point[i];
    const std::string name = "Lighting.point[" + std::to_string(i) + "]";
    UNSEEN_CHECK(l.position_in_cam.allFinite(), "{}.position_in_cam = ({} {} {}) must be finite",
                 name, l.position_in_cam.x(), l.position_in_cam.y(), l.position_in_cam.z());
    CheckColor(l.color_bgr, name + ".color_bgr");
    CheckIntensity(l.intensity, name + ".intensity");
  }
}

void ShadingOptions::Check() const {
  UNSEEN_CHECK(shadow_map_px >= 16 && shadow_map_px <= 8192,
               "ShadingOptions.shadow_map_px = {} must be in [16, 8192]", shadow_map_px);
  UNSEEN_CHECK(std::isfinite(shadow_bias_m) && shadow_bias_m >= 0.0,
               "ShadingOptions.shadow_bias_m = {} must be finite and >= 0", shadow_bias_m);
  UNSEEN_CHECK(std::isfinite(shadow_slope_bias) && shadow_slope_bias >= 0.0,
               "ShadingOptions.shadow_slope_bias = {} must be finite and >= 0",
               shadow_slope_bias);
}

void RenderShaded(const Mesh& mesh, const PinholeCamera& camera, const Rigid3d& cam_from_obj,
                  const PixelRect& roi, const Lighting& lighting, const RenderOptions& options,
                  const ShadingOptions& shading, RenderBuffers* out) {
  lighting.Check();
  shading.Check();
  RenderOptions render_options = options;
  render_options.write_color = true;
  render_options.write_normals = true;
  Render(mesh, camera, cam_from_obj, roi, render_options, out);
  if (out->roi.empty()) return;

  // Shadow maps, one per shadow-casting light (absent when impossible).
  const Rigid3d obj_from_cam = cam_from_obj.Inverse();
  Eigen::Vector3f centre_f;
  float radius_f;
  mesh.BoundingSphere(&centre_f, &radius_f);
  const Eigen::Vector3d centre = centre_f.cast<double>();
  const double radius = std::max(static_cast<double>(radius_f), 1e-6);
  std::vector<std::optional<ShadowMap>> directional_maps(lighting.directional.size());
  std::vector<std::optional<ShadowMap>> point_maps(lighting.point.size());
  for (size_t i = 0; i < lighting.directional.size(); ++i) {
    const DirectionalLight& l = lighting.directional[i];
    if (!l.cast_shadows) continue;
    const Eigen::Vector3d d_obj = obj_from_cam.rotation() * l.direction_in_cam.normalized();
    directional_maps[i] = MakeShadowMap(mesh, centre - 50.0 * radius * d_obj, centre, radius,
                                        shading.shadow_map_px, cam_from_obj);
  }
  for (size_t i = 0; i < lighting.point.size(); ++i) {
    const PointLight& l = lighting.point[i];
    if (!l.cast_shadows) continue;
    point_maps[i] = MakeShadowMap(mesh, obj_from_cam * l.position_in_cam, centre, radius,
                                  shading.shadow_map_px, cam_from_obj);
  }

  const Eigen::Vector3d ambient = lighting.ambient_bgr.cast<double>();
  for (int y = 0; y < out->roi.height(); ++y) {
    const float* depth = out->depth.ptr<float>(y);
    float* color = out->color.ptr<float>(y);
    float* normal = out->normal.ptr<float>(y);
    for (int x = 0; x < out->roi.width(); ++x) {
      if (depth[x] <= 0.0f) continue;
      const Eigen::Vector3d p = camera.Unproject(
          Eigen::Vector2d(out->roi.x0 + x, out->roi.y0 + y), static_cast<double>(depth[x]));
      Eigen::Vector3d n(normal[3 * x], normal[3 * x + 1], normal[3 * x + 2]);
      if (shading.two_sided && n.dot(p) > 0.0) {
        n = -n;
        for (int k = 0; k < 3; ++k) normal[3 * x + k] = static_cast<float>(n[k]);
      }
      Eigen::Vector3d light = ambient;
      for (size_t i = 0; i < lighting.directional.size(); ++i) {
        const DirectionalLight& l = lighting.directional[i];
        const Eigen::Vector3d to_light = -l.direction_in_cam.normalized();
        const double cos_angle = n.dot(to_light);
        if (cos_angle <= 0.0) continue;
        const double visible =
            directional_maps[i] ? Visibility(*directional_maps[i], p, n, to_light, shading) : 1.0;
        light += (l.intensity * cos_angle * visible) * l.color_bgr.cast<double>();
      }
      for (size_t i = 0; i < lighting.point.size(); ++i) {
        const PointLight& l = lighting.point[i];
        const Eigen::Vector3d v = l.position_in_cam - p;
        const double d2 = v.squaredNorm();
        if (!(d2 > 0.0)) continue;
        const Eigen::Vector3d to_light = v / std::sqrt(d2);
        const double cos_angle = n.dot(to_light);
        if (cos_angle <= 0.0) continue;
        const double visible =
            point_maps[i] ? Visibility(*point_maps[i], p, n, to_light, shading) : 1.0;
        light += (l.intensity * cos_angle * visible / d2) * l.color_bgr.cast<double>();
      }
      for (int k = 0; k < 3; ++k) {
        color[3 * x + k] = static_cast<float>(std::clamp(color[3 * x + k] * light[k], 0.0, 1.0));
      }
    }
  }
}

}  // namespace unseen
