// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The rasterizer's resolve pass, internal to render/: texture sampling and the per-triangle
// colour and normal of the visible surface (texture, projective texture, vertex colours
// or the material's diffuse colour). Written by hand because it runs once per rendered
// sample in the tracker's inner loop: per-triangle state is prepared once per run of
// samples of a triangle, texel fetches are four-float loads.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <utility>
#include <vector>
#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "unseen/mesh/mesh.h"

namespace unseen::render_internal {

// Read-only view of a CV_32FC3 image.
struct TextureView {
  const float* data = nullptr;
  int width = 0, height = 0;
  float width_f = 0.0f, height_f = 0.0f;
  size_t step = 0;  // floats per row
  explicit TextureView(const cv::Mat& m = cv::Mat()) {
    if (m.empty()) return;
    data = m.ptr<float>();
    width = m.cols;
    height = m.rows;
    width_f = static_cast<float>(width);
    height_f = static_cast<float>(height);
    step = m.step1();
  }
};

[[gnu::always_inline]] inline void Lerp4(const float* p00, const float* p01, const float* p10, const float* p11,
                  float ax, float ay, float* __restrict out, bool may_read_one_more) {
#if defined(__SSE2__)
  if (may_read_one_more) {  // four-float loads read one float past the texel
    const __m128 a = _mm_loadu_ps(p00), b = _mm_loadu_ps(p01);
    const __m128 c = _mm_loadu_ps(p10), d = _mm_loadu_ps(p11);
    const __m128 vax = _mm_set1_ps(ax);
    const __m128 top = _mm_add_ps(a, _mm_mul_ps(vax, _mm_sub_ps(b, a)));
    const __m128 bottom = _mm_add_ps(c, _mm_mul_ps(vax, _mm_sub_ps(d, c)));
    const __m128 r = _mm_add_ps(top, _mm_mul_ps(_mm_set1_ps(ay), _mm_sub_ps(bottom, top)));
    _mm_storel_pi(reinterpret_cast<__m64*>(out), r);
    _mm_store_ss(out + 2, _mm_movehl_ps(r, r));
    return;
  }
#endif
  const float t0 = p00[0] + ax * (p01[0] - p00[0]), b0 = p10[0] + ax * (p11[0] - p10[0]);
  const float t1 = p00[1] + ax * (p01[1] - p00[1]), b1 = p10[1] + ax * (p11[1] - p10[1]);
  const float t2 = p00[2] + ax * (p01[2] - p00[2]), b2 = p10[2] + ax * (p11[2] - p10[2]);
  out[0] = t0 + ay * (b0 - t0);
  out[1] = t1 + ay * (b1 - t1);
  out[2] = t2 + ay * (b2 - t2);
}

// Index of texel column x wrapped into [0, n).
inline int Wrap(int x, int n) {
  if (static_cast<unsigned>(x) < static_cast<unsigned>(n)) return x;
  x %= n;
  return x < 0 ? x + n : x;
}

// Bilinear sample at OBJ texture coordinates (v up), repeating.
[[gnu::always_inline]] inline void SampleWrap(const TextureView& t, float u, float v,
                                              float* __restrict bgr) {
  float fx = u * t.width_f - 0.5f, fy = (1.0f - v) * t.height_f - 0.5f;
  if (!(std::abs(fx) < 1e8f)) fx = 0.0f;  // NaN or absurd uv
  if (!(std::abs(fy) < 1e8f)) fy = 0.0f;
  const float flx = std::floor(fx), fly = std::floor(fy);
  const int x0 = Wrap(static_cast<int>(flx), t.width);
  const int y0 = Wrap(static_cast<int>(fly), t.height);
  const int x1 = x0 + 1 == t.width ? 0 : x0 + 1;
  const int y1 = y0 + 1 == t.height ? 0 : y0 + 1;
  const float* r0 = t.data + y0 * t.step;
  const float* r1 = t.data + y1 * t.step;
  // Every row but the last has at least one more float after each texel.
  const bool safe = y0 + 1 < t.height && y1 + 1 < t.height;
  Lerp4(r0 + 3 * x0, r0 + 3 * x1, r1 + 3 * x0, r1 + 3 * x1, fx - flx, fy - fly, bgr, safe);
}

// Bilinear sample at a pixel position (pixel-centre convention), clamped to the image.
inline void SampleClamp(const TextureView& t, float x, float y, float* __restrict bgr) {
  x = std::clamp(x, 0.0f, static_cast<float>(t.width - 1));
  y = std::clamp(y, 0.0f, static_cast<float>(t.height - 1));
  const int x0 = std::min(static_cast<int>(x), t.width - 1);
  const int y0 = std::min(static_cast<int>(y), t.height - 1);
  const int x1 = std::min(x0 + 1, t.width - 1), y1 = std::min(y0 + 1, t.height - 1);
  const float* r0 = t.data + y0 * t.step;
  const float* r1 = t.data + y1 * t.step;
  const bool safe = y1 + 1 < t.height;
  Lerp4(r0 + 3 * x0, r0 + 3 * x1, r1 + 3 * x0, r1 + 3 * x1, x - x0, y - y0, bgr, safe);
}

struct ProjectorView {
  Eigen::Matrix3f rotation;
  Eigen::Vector3f translation;
  float fx, fy, cx, cy;
  float max_x, max_y;  // width - 0.5, height - 0.5
  TextureView image;
  // The projector's surface z (CV_32FC1 of the image's size), or null.
  const float* depth = nullptr;
  size_t depth_step = 0;  // floats per row
  float depth_tolerance_m = 0.0f;
};

// Colour and normal of surface points given by their barycentric coordinates (b1, b2) in
// a mesh triangle. Per-triangle data is prepared once per run of pixels of a triangle.
class Shader {
 public:
  // `textures`: the image (mip-map level) to sample for each material.
  Shader(const Mesh& mesh, const std::vector<cv::Mat>& textures) : mesh_(mesh) {
    textures_.reserve(textures.size());
    for (const cv::Mat& t : textures) textures_.emplace_back(t);
    for (const Projector& p : mesh.projectors) {
      ProjectorView v;
      v.rotation = p.cam_from_obj.RotationMatrix().cast<float>();
      v.translation = p.cam_from_obj.translation().cast<float>();
      v.fx = float(p.camera.fx);
      v.fy = float(p.camera.fy);
      v.cx = float(p.camera.cx);
      v.cy = float(p.camera.cy);
      v.max_x = p.image.cols - 0.5f;
      v.max_y = p.image.rows - 0.5f;
      v.image = TextureView(p.image);
      if (!p.depth.empty()) {
        v.depth = p.depth.ptr<float>();
        v.depth_step = p.depth.step1();
      }
      v.depth_tolerance_m = p.depth_tolerance_m;
      projectors_.push_back(v);
    }
  }

  const TextureView* textures() const { return textures_.data(); }

  // Writes the BGR colour of the point (b1, b2) of triangle `tri` to `bgr`.
  void Color(int tri, float b1, float b2, float* bgr) {
    if (tri != color_tri_) PrepareColor(tri);
    if (kind_ == Kind::kProjective && ProjectiveColor(b1, b2, bgr)) return;
    if (fallback_kind_ == Kind::kTexture) {
      SampleWrap(*texture_, uv0_.x() + b1 * duv1_.x() + b2 * duv2_.x(),
                 uv0_.y() + b1 * duv1_.y() + b2 * duv2_.y(), bgr);
      return;
    }
    for (int k = 0; k < 3; ++k) bgr[k] = c0_[k] + b1 * dc1_[k] + b2 * dc2_[k];
  }

  // Unit normal in the object frame.
  Eigen::Vector3f Normal(int tri, float b1, float b2) {
    if (tri != normal_tri_) {
      normal_tri_ = tri;
      const Eigen::Vector3i& t = mesh_.triangles[tri];
      if (!mesh_.normals.empty()) {
        n0_ = mesh_.normals[t[0]];
        dn1_ = mesh_.normals[t[1]] - n0_;
        dn2_ = mesh_.normals[t[2]] - n0_;
      } else {
        const Eigen::Vector3f& v0 = mesh_.vertices[t[0]];
        n0_ = (mesh_.vertices[t[1]] - v0).cross(mesh_.vertices[t[2]] - v0);
        dn1_.setZero();
        dn2_.setZero();
      }
    }
    const Eigen::Vector3f n = n0_ + b1 * dn1_ + b2 * dn2_;
    const float len = n.norm();
    return len > 0.0f ? Eigen::Vector3f(n / len) : Eigen::Vector3f::Zero();
  }

 private:
  enum class Kind { kTexture, kProjective, kVertexColor, kConstant };

  void PrepareColor(int tri) {
    color_tri_ = tri;
    const Eigen::Vector3i& t = mesh_.triangles[tri];
    const int m = mesh_.triangle_materials.empty() ? (mesh_.materials.empty() ? -1 : 0)
                                                   : mesh_.triangle_materials[tri];
    // The colour without projectors: texture, vertex colours, diffuse, white.
    if (m >= 0 && textures_[m].data != nullptr && !mesh_.uvs.empty()) {
      kind_ = Kind::kTexture;
      texture_ = &textures_[m];
      uv0_ = mesh_.uvs[t[0]];
      duv1_ = mesh_.uvs[t[1]] - uv0_;
      duv2_ = mesh_.uvs[t[2]] - uv0_;
    } else if (!mesh_.colors_bgr.empty()) {
      kind_ = Kind::kVertexColor;
      c0_ = mesh_.colors_bgr[t[0]];
      dc1_ = mesh_.colors_bgr[t[1]] - c0_;
      dc2_ = mesh_.colors_bgr[t[2]] - c0_;
    } else {
      kind_ = Kind::kConstant;
      c0_ = m >= 0 ? mesh_.materials[m].diffuse_bgr : Eigen::Vector3f::Ones();
      dc1_.setZero();
      dc2_.setZero();
    }
    if (!projectors_.empty()) {
      fallback_kind_ = kind_;
      kind_ = Kind::kProjective;
      PrepareProjectors(tri);
    } else {
      fallback_kind_ = kind_;
    }
  }

  // The projectors the triangle's centre faces, best facing first, each with the triangle
  // in its frame (the point of barycentric (b1, b2) is affine in them: q = q0 + b1 dq1 +
  // b2 dq2). A pixel takes the first of them that sees it (in its image, not hidden), so
  // most pixels test one projector (the choice is per triangle rather than per pixel).
  // Cached per triangle: small triangles are entered by many runs of pixels.
  void PrepareProjectors(int tri) {
    if (prepared_.empty()) prepared_.assign(mesh_.triangles.size(), {-1, 0});
    auto& [begin, count] = prepared_[tri];
    if (begin < 0) {
      const Eigen::Vector3i& t = mesh_.triangles[tri];
      const Eigen::Vector3f p0 = mesh_.vertices[t[0]];
      const Eigen::Vector3f dp1 = mesh_.vertices[t[1]] - p0;
      const Eigen::Vector3f dp2 = mesh_.vertices[t[2]] - p0;
      const Eigen::Vector3f face_normal = dp1.cross(dp2);
      begin = static_cast<int>(candidates_.size());
      for (size_t k = 0; k < projectors_.size(); ++k) {
        const ProjectorView& v = projectors_[k];
        ProjectorTriangle pt;
        pt.projector = static_cast<int>(k);
        const Eigen::Vector3f q0 = v.rotation * p0 + v.translation;
        const Eigen::Vector3f dq1 = v.rotation * dp1;
        const Eigen::Vector3f dq2 = v.rotation * dp2;
        // The triangle's plane faces the projector at every point of it or at none
        // (normal . q is the same for all q of the plane): tested once, at the centre.
        const Eigen::Vector3f centre = q0 + (dq1 + dq2) / 3.0f;
        const float facing = -(v.rotation * face_normal).dot(centre);
        if (!(facing > 0.0f && centre.z() > 0.0f)) continue;
        pt.score = facing / centre.norm();
        // Rows of K [q0 dq1 dq2]: the projector's homogeneous pixel of (b1, b2).
        const Eigen::Vector3f kx(v.fx, 0.0f, v.cx), ky(0.0f, v.fy, v.cy);
        pt.x = Eigen::Vector3f(kx.dot(q0), kx.dot(dq1), kx.dot(dq2));
        pt.y = Eigen::Vector3f(ky.dot(q0), ky.dot(dq1), ky.dot(dq2));
        pt.z = Eigen::Vector3f(q0.z(), dq1.z(), dq2.z());
        candidates_.push_back(pt);
      }
      count = static_cast<int>(candidates_.size()) - begin;
      std::sort(
          candidates_.begin() + begin, candidates_.end(),
          [](const ProjectorTriangle& a, const ProjectorTriangle& b) { return a.score > b.score; });
    }
    candidates_begin_ = begin;
    candidates_end_ = begin + count;
  }

  bool ProjectiveColor(float b1, float b2, float* bgr) const {
    for (int c = candidates_begin_; c < candidates_end_; ++c) {
      const ProjectorTriangle& pt = candidates_[c];
      const ProjectorView& v = projectors_[pt.projector];
      const float z = pt.z[0] + b1 * pt.z[1] + b2 * pt.z[2];
      if (!(z > 0.0f)) continue;
      const float inv_z = 1.0f / z;
      const float x = (pt.x[0] + b1 * pt.x[1] + b2 * pt.x[2]) * inv_z;
      const float y = (pt.y[0] + b1 * pt.y[1] + b2 * pt.y[2]) * inv_z;
      if (!(x >= -0.5f && y >= -0.5f && x < v.max_x && y < v.max_y)) continue;
      if (v.depth) {
        // Hidden from the projector: behind the surface it saw there, or it saw none.
        // (x, y >= -0.5: adding a half and truncating rounds to the nearest pixel.)
        const int px = std::min(static_cast<int>(x + 0.5f), v.image.width - 1);
        const int py = std::min(static_cast<int>(y + 0.5f), v.image.height - 1);
        const float seen = v.depth[py * v.depth_step + px];
        if (!(seen > 0.0f) || z > seen + v.depth_tolerance_m) continue;
      }
      SampleClamp(v.image, x, y, bgr);
      return true;
    }
    return false;
  }

  const Mesh& mesh_;
  std::vector<TextureView> textures_;
  std::vector<ProjectorView> projectors_;
  // The triangle prepared for Color().
  int color_tri_ = -1;
  Kind kind_ = Kind::kConstant, fallback_kind_ = Kind::kConstant;
  const TextureView* texture_ = nullptr;
  Eigen::Vector2f uv0_ = Eigen::Vector2f::Zero(), duv1_ = uv0_, duv2_ = uv0_;
  Eigen::Vector3f c0_ = Eigen::Vector3f::Zero(), dc1_ = c0_, dc2_ = c0_;
  // A triangle in a projector's frame.
  struct ProjectorTriangle {
    // The projector's pixel of the point (b1, b2) is (x . b, y . b) / (z . b), b = (1, b1, b2).
    Eigen::Vector3f x, y, z;
    float score = 0.0f;  // how squarely the triangle's centre faces the projector
    int projector = 0;
  };
  // Per triangle (first, count) of its candidates_, first < 0 until prepared.
  std::vector<std::pair<int, int>> prepared_;
  std::vector<ProjectorTriangle> candidates_;
  int candidates_begin_ = 0, candidates_end_ = 0;  // of the prepared triangle
  // The triangle prepared for Normal().
  int normal_tri_ = -1;
  Eigen::Vector3f n0_ = Eigen::Vector3f::Zero(), dn1_ = n0_, dn2_ = n0_;
};

}  // namespace unseen::render_internal
