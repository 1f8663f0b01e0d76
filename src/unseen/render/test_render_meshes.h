// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Test support (header only, used by the render tests): a small camera, quads, a cube and
// a sphere, random textures and the exact depth of a plane.
#pragma once

#include <cmath>
#include <vector>

#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/mesh/mesh.h"

namespace unseen::render_testing {

// A small camera with unequal focal lengths and its principal point off the centre.
inline PinholeCamera TestCamera(int width = 160, int height = 120) {
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
inline Mesh MakeQuad(const std::vector<Eigen::Vector3f>& corners) {
  Mesh m;
  m.vertices = corners;
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

// A 0.6 x 0.5 m quad tilted about both axes (z from 0.1 to -0.1 across it), in the object
// frame.
inline Mesh MakeTiltedQuad() {
  return MakeQuad({{-0.3f, -0.25f, 0.1f}, {-0.3f, 0.25f, 0.0f}, {0.3f, 0.25f, -0.1f},
                   {0.3f, -0.25f, 0.0f}});
}

// A camera-facing quad at depth z covering pixel rectangle [u0, u1] x [v0, v1] (pixels).
// Seen from the camera, counter-clockwise with y down means: top-left, bottom-left,
// bottom-right, top-right.
inline Mesh MakeScreenQuad(const PinholeCamera& cam, double u0, double v0, double u1, double v1,
                    double z) {
  auto at = [&](double u, double v) {
    return cam.Unproject(Eigen::Vector2d(u, v), z).cast<float>().eval();
  };
  return MakeQuad({at(u0, v0), at(u0, v1), at(u1, v1), at(u1, v0)});
}

// Axis-aligned cube centred on the origin, triangles counter-clockwise seen from outside.
inline Mesh MakeCube(float edge) {
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
inline Mesh MakeSphere(float radius, int rings, int segments) {
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

inline Rigid3d Pose(const Eigen::Vector3d& rotation_vector, const Eigen::Vector3d& t) {
  return Rigid3d(ExpSO3(rotation_vector), t);
}

inline cv::Mat RandomTexture(int w, int h, unsigned seed) {
  cv::Mat t(h, w, CV_32FC3);
  cv::RNG rng(seed);
  rng.fill(t, cv::RNG::UNIFORM, 0.0, 1.0);
  return t;
}

// Ray-plane depth at pixel (u, v) for the plane n . p = d (camera frame).
inline double PlaneDepth(const PinholeCamera& cam, double u, double v, const Eigen::Vector3d& n,
                  double d) {
  const Eigen::Vector3d ray((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
  return d / n.dot(ray);
}

// Float rounding plus the effect of snapping vertices to 1/256 px: the depth gradient
// times 1/256 px.
inline double DepthTolerance(const PinholeCamera& cam, double u, double v, const Eigen::Vector3d& n,
                      double d) {
  const double z = PlaneDepth(cam, u, v, n, d);
  const double gradient = std::abs(PlaneDepth(cam, u + 1, v, n, d) - z) +
                          std::abs(PlaneDepth(cam, u, v + 1, n, d) - z);
  return 1e-6 * z + gradient / 256.0;
}

}  // namespace unseen::render_testing
