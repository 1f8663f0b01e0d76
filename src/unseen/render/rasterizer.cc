// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/render/rasterizer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include <Eigen/Geometry>
#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "unseen/render/mipmap.h"
#include "unseen/render/surface_shader.h"
#include "unseen/util/error.h"

namespace unseen {

void RenderOptions::Check() const {
  UNSEEN_CHECK(std::isfinite(near_m) && near_m > 0.0,
               "RenderOptions.near_m = {} must be positive and finite (metres)", near_m);
}

namespace {

using render_internal::SampleWrap;
using render_internal::Shader;
using render_internal::TextureView;

constexpr int kSubpixelBits = 8;
// Regions smaller than this (pixels) are resolved on one thread: not worth the fork.
constexpr int kParallelResolvePixels = 8192;
constexpr int64_t kSubpixel = 1 << kSubpixelBits;  // screen positions snap to 1/256 px
constexpr double kGuardPx = 4096.0;  // triangles are clipped to the image grown by this
constexpr int kMaxImageSide = 32768;  // keeps snapped coordinates in int32
constexpr int kMaxMipmapLevels = 12;
constexpr int kSmallBoxPx = 6;  // bounding boxes up to this many pixels skip span set-up

// A mesh vertex after projection (one per vertex, shared by its triangles).
struct ProjectedVertex {
  int32_t x, y;  // pixel position * kSubpixel, rounded
  float inv_z;   // 1 / camera-frame z, 1/m
  int32_t ok;    // 1: z >= near and inside the guard band; 0: the triangle needs clipping
};

// A corner of a triangle handed to the scan converter: snapped position, 1/z, and two
// attributes interpolated perspective-correctly: either the barycentric coordinates
// (b1, b2) of the point in its mesh triangle (the corners of an unclipped triangle are
// (0, 0), (1, 0), (0, 1)) or its texture coordinates (u, v).
struct RasterVertex {
  int64_t x, y;
  float inv_z;
  float w1, w2;
};

// Where the scan converter writes; every pointer addresses image pixel (roi.x0, roi.y0).
struct RasterTarget {
  PixelRect roi;
  float* inv_z = nullptr;  // z-buffer of 1/z, 0 = empty
  size_t z_stride = 0;     // floats per row
  int32_t* ids = nullptr;
  size_t id_stride = 0;
  float* weights = nullptr;  // (w1/z, w2/z) per pixel
  size_t w_stride = 0;       // floats per row
};

// floor and ceil of a / kSubpixel (arithmetic shifts, C++20).
inline int64_t FloorPixel(int64_t a) { return a >> kSubpixelBits; }
inline int64_t CeilPixel(int64_t a) { return -((-a) >> kSubpixelBits); }

// Top-left rule with y down: an edge whose inward normal (a, b) points right (a > 0, a
// "left" edge) or, when horizontal, down (a "top" edge) owns the pixel centres on it.
inline int64_t FillBias(int64_t a, int64_t b) { return (a > 0 || (a == 0 && b > 0)) ? 0 : -1; }

// q = floor(a / b), r = a - q b in [0, b), for b > 0 and |a| < 2^53: a double division
// guesses, one integer correction makes it exact.
inline void FloorDivMod(int64_t a, int64_t b, int64_t* q, int64_t* r) {
  int64_t qq = static_cast<int64_t>(std::floor(double(a) / double(b)));
  int64_t rr = a - qq * b;
  if (rr < 0) {
    --qq;
    rr += b;
  } else if (rr >= b) {
    ++qq;
    rr -= b;
  }
  *q = qq;
  *r = rr;
}

// One edge function walked row by row. Along a row E(k) = e + k * sx (k pixels from the
// bounding box's left column); the pixels with E >= 0 are k >= -floor(e / sx) for sx > 0
// and k <= floor(e / -sx) for sx < 0. floor(e / |sx|) is stepped exactly from row to row
// (Bresenham-style, e += sy), so spans cost no division per row.
class EdgeWalker {
 public:
  EdgeWalker(int64_t e, int64_t sx, int64_t sy) {
    left_ = sx > 0;
    right_ = sx < 0;
    flat_ = sx == 0;
    if (flat_) {
      q_ = e;  // the edge function itself; r_ stays 0 < s_ = 1
      dq_ = sy;
      return;
    }
    s_ = sx > 0 ? sx : -sx;
    FloorDivMod(e, s_, &q_, &r_);
    FloorDivMod(sy, s_, &dq_, &dr_);
  }
  // Narrows [*lo, *hi]; clears *ok when no pixel of the row is inside. Branch-free: the
  // edge's kind changes from triangle to triangle.
  void Narrow(int64_t* lo, int64_t* hi, bool* ok) const {
    *lo = left_ ? std::max(*lo, -q_) : *lo;
    *hi = right_ ? std::min(*hi, q_) : *hi;
    *ok &= !(flat_ && q_ < 0);
  }
  void NextRow() {
    q_ += dq_;
    r_ += dr_;
    const bool carry = r_ >= s_;
    r_ -= carry ? s_ : 0;
    q_ += carry;
  }

 private:
  bool left_, right_, flat_;
  int64_t q_, r_ = 0, s_ = 1, dq_, dr_ = 0;
};

// a * b + c, fused where the hardware can, so that every code path rounds alike.
inline float MulAdd(float a, float b, float c) {
#if defined(__FMA__)
  return std::fma(a, b, c);
#else
  return a * b + c;
#endif
}

// Affine screen-space interpolation f(x, y) = f0 + gx (x - x_ref) + gy (y - y_ref) of
// the corner values f0, f1, f2 (pixels).
struct Plane {
  float f0, gx, gy;
};

// Scan-converts one triangle. `cull`: drop it when it faces away from the camera.
// Front-facing triangles (counter-clockwise seen from outside) have negative signed area
// in y-down pixel coordinates.
template <bool kAttributes, bool kIds>
void RasterTriangle(RasterVertex v0, RasterVertex v1, RasterVertex v2, bool cull, int32_t id,
                    const RasterTarget& t) {
  int64_t area2 = (v1.x - v0.x) * (v2.y - v0.y) - (v2.x - v0.x) * (v1.y - v0.y);
  if (area2 < 0) {
    std::swap(v1, v2);
    area2 = -area2;
  } else if (area2 == 0 || cull) {
    return;
  }
  const int64_t min_x = std::min({v0.x, v1.x, v2.x}), max_x = std::max({v0.x, v1.x, v2.x});
  const int64_t min_y = std::min({v0.y, v1.y, v2.y}), max_y = std::max({v0.y, v1.y, v2.y});
  const int x_lo = static_cast<int>(std::max<int64_t>(t.roi.x0, CeilPixel(min_x)));
  const int x_hi = static_cast<int>(std::min<int64_t>(t.roi.x1 - 1, FloorPixel(max_x)));
  const int y_lo = static_cast<int>(std::max<int64_t>(t.roi.y0, CeilPixel(min_y)));
  const int y_hi = static_cast<int>(std::min<int64_t>(t.roi.y1 - 1, FloorPixel(max_y)));
  if (x_lo > x_hi || y_lo > y_hi) return;

  // Edge functions E_i = a_i x + b_i y + c_i (x, y in 1/256 px), E_i opposite v_i, positive
  // inside, E_i(v_i) = area2. Exact in 64 bits: |coordinates| < 2^24.
  const int64_t a0 = v1.y - v2.y, b0 = v2.x - v1.x;
  const int64_t a1 = v2.y - v0.y, b1 = v0.x - v2.x;
  const int64_t a2 = v0.y - v1.y, b2 = v1.x - v0.x;
  const int64_t bias0 = FillBias(a0, b0), bias1 = FillBias(a1, b1), bias2 = FillBias(a2, b2);

  // Interpolation planes, set up once the triangle is known to cover a pixel.
  Plane pz{}, pw1{}, pw2{};
  const float x_ref = static_cast<float>(v0.x) / kSubpixel;
  const float y_ref = static_cast<float>(v0.y) / kSubpixel;
  auto setup_planes = [&] {
    // Barycentric l_k = E_k / area2; dl_k/dx = a_k * 256 / area2 per pixel.
    const double s = static_cast<double>(kSubpixel) / static_cast<double>(area2);
    const double l1x = a1 * s, l2x = a2 * s, l1y = b1 * s, l2y = b2 * s;
    auto make_plane = [&](double f0, double f1, double f2) {
      return Plane{static_cast<float>(f0), static_cast<float>(l1x * (f1 - f0) + l2x * (f2 - f0)),
                   static_cast<float>(l1y * (f1 - f0) + l2y * (f2 - f0))};
    };
    pz = make_plane(v0.inv_z, v1.inv_z, v2.inv_z);
    if constexpr (kAttributes) {
      // w / z is affine in screen space (perspective-correct interpolation).
      pw1 = make_plane(double(v0.inv_z) * v0.w1, double(v1.inv_z) * v1.w1,
                       double(v2.inv_z) * v2.w1);
      pw2 = make_plane(double(v0.inv_z) * v0.w2, double(v1.inv_z) * v1.w2,
                       double(v2.inv_z) * v2.w2);
    }
  };
  // Row pointers address image column 0 of the roi-sized buffers.
  float* const z_base = t.inv_z - t.roi.x0;
  int32_t* const id_base = kIds ? t.ids - t.roi.x0 : nullptr;
  float* const w_base = kAttributes ? t.weights - 2 * t.roi.x0 : nullptr;
  const ptrdiff_t z_stride = t.z_stride, id_stride = t.id_stride, w_stride = t.w_stride;
  // Depth test and write of pixels [x_begin, x_end] of row y (all inside).
  auto write_span = [&](int y, int x_begin, int x_end) {
    const float dy = static_cast<float>(y) - y_ref;
    const float z_row = MulAdd(pz.gy, dy, pz.f0);
    float w1_row = 0.0f, w2_row = 0.0f;
    if constexpr (kAttributes) {
      w1_row = MulAdd(pw1.gy, dy, pw1.f0);
      w2_row = MulAdd(pw2.gy, dy, pw2.f0);
    }
    const ptrdiff_t row = y - t.roi.y0;
    float* z_ptr = z_base + row * z_stride;
    int32_t* id_ptr = kIds ? id_base + row * id_stride : nullptr;
    float* w_ptr = kAttributes ? w_base + row * w_stride : nullptr;
    float dx = static_cast<float>(x_begin) - x_ref;  // exact, and so are its increments
    for (int x = x_begin; x <= x_end; ++x, dx += 1.0f) {
      const float inv_z = MulAdd(pz.gx, dx, z_row);
      if (inv_z > z_ptr[x]) {
        z_ptr[x] = inv_z;
        if constexpr (kIds) id_ptr[x] = id;
        if constexpr (kAttributes) {
          w_ptr[2 * x] = MulAdd(pw1.gx, dx, w1_row);
          w_ptr[2 * x + 1] = MulAdd(pw2.gx, dx, w2_row);
        }
      }
    }
  };

  if ((x_hi - x_lo + 1) * (y_hi - y_lo + 1) <= kSmallBoxPx) {
    // Tiny triangles (dense meshes): test the few pixel centres directly.
    bool ready = false;
    for (int y = y_lo; y <= y_hi; ++y) {
      const int64_t py = y * kSubpixel;
      for (int x = x_lo; x <= x_hi; ++x) {
        const int64_t px = x * kSubpixel;
        const int64_t e0 = a0 * (px - v1.x) + b0 * (py - v1.y) + bias0;
        const int64_t e1 = a1 * (px - v2.x) + b1 * (py - v2.y) + bias1;
        const int64_t e2 = a2 * (px - v0.x) + b2 * (py - v0.y) + bias2;
        if ((e0 | e1 | e2) < 0) continue;
        if (!ready) {
          setup_planes();
          ready = true;
        }
        write_span(y, x, x);
      }
    }
    return;
  }

  const int64_t px = x_lo * kSubpixel, py = y_lo * kSubpixel;
  EdgeWalker edge0(a0 * (px - v1.x) + b0 * (py - v1.y) + bias0, a0 * kSubpixel, b0 * kSubpixel);
  EdgeWalker edge1(a1 * (px - v2.x) + b1 * (py - v2.y) + bias1, a1 * kSubpixel, b1 * kSubpixel);
  EdgeWalker edge2(a2 * (px - v0.x) + b2 * (py - v0.y) + bias2, a2 * kSubpixel, b2 * kSubpixel);
  setup_planes();
  for (int y = y_lo; y <= y_hi; ++y, edge0.NextRow(), edge1.NextRow(), edge2.NextRow()) {
    // The span [x_lo + lo, x_lo + hi] of centres inside all three edges, exactly.
    int64_t lo = 0, hi = x_hi - x_lo;
    bool ok = true;
    edge0.Narrow(&lo, &hi, &ok);
    edge1.Narrow(&lo, &hi, &ok);
    edge2.Narrow(&lo, &hi, &ok);
    if (!ok || lo > hi) continue;
    write_span(y, x_lo + static_cast<int>(lo), x_lo + static_cast<int>(hi));
  }
}

// A polygon corner during clipping: camera-frame position, barycentric coordinates in
// the mesh triangle, and the mesh vertex it is (-1 when created by clipping).
struct ClipVertex {
  Eigen::Vector3d p;
  double b1, b2;
  int vertex;
};

// Sutherland-Hodgman against the half-space plane.head(3) . p + plane(3) >= 0.
int ClipPolygon(const ClipVertex* in, int n, const Eigen::Vector4d& plane, ClipVertex* out) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const ClipVertex& a = in[i];
    const ClipVertex& b = in[(i + 1) % n];
    const double da = plane.head<3>().dot(a.p) + plane[3];
    const double db = plane.head<3>().dot(b.p) + plane[3];
    if (da >= 0.0) out[m++] = a;
    if ((da >= 0.0) != (db >= 0.0)) {
      const double s = da / (da - db);
      out[m++] = {a.p + s * (b.p - a.p), a.b1 + s * (b.b1 - a.b1), a.b2 + s * (b.b2 - a.b2), -1};
    }
  }
  return m;
}

struct ClipContext {
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation;
  double fx, fy, cx, cy;
  Eigen::Vector4d planes[5];  // near, then the guard band left, right, top, bottom
  double lo_x, hi_x, lo_y, hi_y;  // guard band, px
};

// The slow path for a triangle with a corner behind the near plane or far outside the
// image: clip it in the camera frame, then scan-convert the fan of the polygon.
// `attributes`: the values at the triangle's corners.
template <bool kAttributes, bool kIds>
void RasterClipped(const Mesh& mesh, const Eigen::Vector3i& tri, int32_t id, bool cull,
                   const Eigen::Vector2f attributes[3],
                   const std::vector<ProjectedVertex>& projected, const ClipContext& c,
                   const RasterTarget& target) {
  ClipVertex a[16], b[16];
  for (int k = 0; k < 3; ++k) {
    a[k] = {c.rotation * mesh.vertices[tri[k]].cast<double>() + c.translation,
            k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0, tri[k]};
  }
  if (cull) {
    const Eigen::Vector3d n = (a[1].p - a[0].p).cross(a[2].p - a[0].p);
    if (!(n.dot(a[0].p) < 0.0)) return;  // back-facing or edge-on
  }
  int n = 3;
  ClipVertex* in = a;
  ClipVertex* out = b;
  for (const Eigen::Vector4d& plane : c.planes) {
    n = ClipPolygon(in, n, plane, out);
    if (n < 3) return;
    std::swap(in, out);
  }
  RasterVertex r[16];
  const Eigen::Vector2f d1 = attributes[1] - attributes[0], d2 = attributes[2] - attributes[0];
  for (int k = 0; k < n; ++k) {
    const ClipVertex& v = in[k];
    const Eigen::Vector2f w = attributes[0] + float(v.b1) * d1 + float(v.b2) * d2;
    if (v.vertex >= 0 && projected[v.vertex].ok) {
      // Same snapped position as in the fast path, so shared edges stay watertight.
      const ProjectedVertex& q = projected[v.vertex];
      r[k] = {q.x, q.y, q.inv_z, w.x(), w.y()};
      continue;
    }
    const double inv_z = 1.0 / v.p.z();
    const double px = std::clamp(c.fx * v.p.x() * inv_z + c.cx, c.lo_x, c.hi_x);
    const double py = std::clamp(c.fy * v.p.y() * inv_z + c.cy, c.lo_y, c.hi_y);
    r[k] = {std::llround(px * kSubpixel), std::llround(py * kSubpixel), float(inv_z), w.x(),
            w.y()};
  }
  // The polygon keeps the triangle's orientation; culling was decided above.
  for (int k = 1; k + 1 < n; ++k) {
    RasterTriangle<kAttributes, kIds>(r[0], r[k], r[k + 1], false, id, target);
  }
}

// Per material, the texture area and image area of the drawn triangles, to choose a
// mip-map level: texels per pixel = texels * texture_size / (pixels / 256^2).
struct TexelStats {
  std::vector<double> texture_size;  // texels of each material's texture (0: none)
  std::vector<double> texels;        // sum of |uv cross products| (twice the uv area)
  std::vector<double> pixels;        // sum of |area2| (twice the area in 1/256 px units)
};

// Scan-converts every triangle. The interpolated attributes are the texture coordinates
// `uvs` (per vertex) or, when null, the barycentric coordinates in the mesh triangle.
// `stats`, when not null, is accumulated over the triangles not clipped.
template <bool kAttributes, bool kIds>
void RasterMesh(const Mesh& mesh, const Eigen::Vector2f* uvs,
                const std::vector<ProjectedVertex>& projected, bool cull, const ClipContext& clip,
                const RasterTarget& target, TexelStats* stats) {
  const Eigen::Vector2f corners[3] = {{0.0f, 0.0f}, {1.0f, 0.0f}, {0.0f, 1.0f}};
  const int64_t x_first = target.roi.x0, x_last = target.roi.x1 - 1;
  const int64_t y_first = target.roi.y0, y_last = target.roi.y1 - 1;
  const uint32_t nv = static_cast<uint32_t>(mesh.vertices.size());
  const int nt = mesh.num_triangles();
  for (int t = 0; t < nt; ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    if (static_cast<uint32_t>(tri[0]) >= nv || static_cast<uint32_t>(tri[1]) >= nv ||
        static_cast<uint32_t>(tri[2]) >= nv) {
      ThrowError("Render: mesh triangle {} has vertex indices ({}, {}, {}), range is [0, {})", t,
                 tri[0], tri[1], tri[2], nv);
    }
    const ProjectedVertex& p0 = projected[tri[0]];
    const ProjectedVertex& p1 = projected[tri[1]];
    const ProjectedVertex& p2 = projected[tri[2]];
    Eigen::Vector2f w[3] = {corners[0], corners[1], corners[2]};
    auto load_attributes = [&] {
      if (kAttributes && uvs != nullptr) {
        w[0] = uvs[tri[0]];
        w[1] = uvs[tri[1]];
        w[2] = uvs[tri[2]];
      }
    };
    if (p0.ok & p1.ok & p2.ok) {
      // Cheap rejections before the set-up: culled, degenerate, no pixel centre in the roi.
      const int64_t area2 = int64_t(p1.x - p0.x) * (p2.y - p0.y) -
                            int64_t(p2.x - p0.x) * (p1.y - p0.y);
      if (area2 == 0 || (cull && area2 > 0)) continue;
      if (stats != nullptr) {
        const int m = mesh.triangle_materials.empty() ? 0 : mesh.triangle_materials[t];
        if (stats->texture_size[m] > 0.0) {
          const Eigen::Vector2f& u0 = mesh.uvs[tri[0]];
          const Eigen::Vector2f d1 = mesh.uvs[tri[1]] - u0, d2 = mesh.uvs[tri[2]] - u0;
          stats->texels[m] += std::abs(double(d1.x()) * d2.y() - double(d1.y()) * d2.x());
          stats->pixels[m] += std::abs(double(area2));
        }
      }
      const int64_t x_lo = std::max(x_first, CeilPixel(std::min({p0.x, p1.x, p2.x})));
      const int64_t x_hi = std::min(x_last, FloorPixel(std::max({p0.x, p1.x, p2.x})));
      const int64_t y_lo = std::max(y_first, CeilPixel(std::min({p0.y, p1.y, p2.y})));
      const int64_t y_hi = std::min(y_last, FloorPixel(std::max({p0.y, p1.y, p2.y})));
      if (x_lo > x_hi || y_lo > y_hi) continue;
      load_attributes();
      RasterTriangle<kAttributes, kIds>({p0.x, p0.y, p0.inv_z, w[0].x(), w[0].y()},
                                        {p1.x, p1.y, p1.inv_z, w[1].x(), w[1].y()},
                                        {p2.x, p2.y, p2.inv_z, w[2].x(), w[2].y()}, cull, t,
                                        target);
    } else {
      load_attributes();
      RasterClipped<kAttributes, kIds>(mesh, tri, t, cull, w, projected, clip, target);
    }
  }
}

// Checks of the mesh that cost O(1) or O(materials); vertex values and indices are
// checked in the passes that read them anyway.
void CheckMeshForRender(const Mesh& mesh) {
  const size_t nv = mesh.vertices.size();
  UNSEEN_CHECK(!mesh.triangles.empty(), "Render: mesh has no triangles");
  UNSEEN_CHECK(nv > 0, "Render: mesh has no vertices");
  UNSEEN_CHECK(mesh.normals.empty() || mesh.normals.size() == nv,
               "Render: mesh has {} normals for {} vertices", mesh.normals.size(), nv);
  UNSEEN_CHECK(mesh.uvs.empty() || mesh.uvs.size() == nv, "Render: mesh has {} uvs for {} vertices",
               mesh.uvs.size(), nv);
  UNSEEN_CHECK(mesh.colors_bgr.empty() || mesh.colors_bgr.size() == nv,
               "Render: mesh has {} colours for {} vertices", mesh.colors_bgr.size(), nv);
  UNSEEN_CHECK(mesh.triangle_materials.empty() ||
                   mesh.triangle_materials.size() == mesh.triangles.size(),
               "Render: mesh has {} triangle materials for {} triangles",
               mesh.triangle_materials.size(), mesh.triangles.size());
  for (const Material& m : mesh.materials) {
    UNSEEN_CHECK(m.texture.empty() || (m.texture.type() == CV_32FC3 && m.texture.dims == 2),
                 "Render: material '{}' texture must be CV_32FC3 (type is {})", m.name,
                 m.texture.type());
  }
  for (size_t p = 0; p < mesh.projectors.size(); ++p) {
    UNSEEN_CHECK(!mesh.projectors[p].image.empty() &&
                     mesh.projectors[p].image.type() == CV_32FC3,
                 "Render: mesh projector {} has no CV_32FC3 image", p);
    mesh.projectors[p].camera.Check(fmt::format("Render: mesh projector {} camera", p));
    UNSEEN_CHECK(mesh.projectors[p].cam_from_obj.IsValid(),
                 "Render: mesh projector {} cam_from_obj is not a valid pose ({})", p,
                 mesh.projectors[p].cam_from_obj.ToString());
    const cv::Mat& depth = mesh.projectors[p].depth;
    UNSEEN_CHECK(depth.empty() || (depth.type() == CV_32FC1 &&
                                   depth.size() == mesh.projectors[p].image.size()),
                 "Render: mesh projector {} depth must be empty or CV_32FC1 of its image's size",
                 p);
  }
}

// z[i] = z[i] > 0 ? 1 / z[i] : 0.
void InvertPositive(float* z, int n) {
  int i = 0;
#if defined(__SSE2__)
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
  for (; i + 4 <= n; i += 4) {
    const __m128 v = _mm_loadu_ps(z + i);
    const __m128 positive = _mm_cmpgt_ps(v, zero);
    const __m128 safe = _mm_or_ps(_mm_and_ps(positive, v), _mm_andnot_ps(positive, one));
    _mm_storeu_ps(z + i, _mm_and_ps(positive, _mm_div_ps(one, safe)));
  }
#endif
  for (; i < n; ++i) z[i] = z[i] > 0.0f ? 1.0f / z[i] : 0.0f;
}

void ReleaseOutputs(RenderBuffers* out) {
  out->color.release();
  out->depth.release();
  out->mask.release();
  out->triangle_id.release();
  out->normal.release();
}

}  // namespace

namespace {

// The colour of rows [row_begin, row_end) (row_begin even) of `out` with one shading of
// each 2x2 block of samples that one triangle covers whole, at the mean of its samples'
// barycentric coordinates (RenderOptions::shade_quads); the other samples one by one.
// Expects the resolved mask, metric depth, the triangle ids and the weights (b / z).
void ResolveQuadColors(RenderBuffers& out, const cv::Mat& ids, int row_begin, int row_end,
                       Shader* shader) {
  const int width = out.mask.cols;
  auto shade = [&](int y, int x) {
    float* color = out.color.ptr<float>(y) + 3 * x;
    if (!out.mask.ptr<uint8_t>(y)[x]) {
      color[0] = color[1] = color[2] = 0.0f;
      return;
    }
    const float z = out.depth.ptr<float>(y)[x];
    const float* w = out.scratch_weights.ptr<float>(y) + 2 * x;
    shader->Color(ids.ptr<int32_t>(y)[x], w[0] * z, w[1] * z, color);
  };
  int y = row_begin;
  for (; y + 1 < row_end; y += 2) {
    const uint8_t* m0 = out.mask.ptr<uint8_t>(y);
    const uint8_t* m1 = out.mask.ptr<uint8_t>(y + 1);
    const int32_t* id0 = ids.ptr<int32_t>(y);
    const int32_t* id1 = ids.ptr<int32_t>(y + 1);
    const float* z0 = out.depth.ptr<float>(y);
    const float* z1 = out.depth.ptr<float>(y + 1);
    const float* w0 = out.scratch_weights.ptr<float>(y);
    const float* w1 = out.scratch_weights.ptr<float>(y + 1);
    float* c0 = out.color.ptr<float>(y);
    float* c1 = out.color.ptr<float>(y + 1);
    int x = 0;
    for (; x + 1 < width; x += 2) {
      const int32_t id = id0[x];
      if (m0[x] && m0[x + 1] && m1[x] && m1[x + 1] && id0[x + 1] == id && id1[x] == id &&
          id1[x + 1] == id) {
        const float b1 = 0.25f * (w0[2 * x] * z0[x] + w0[2 * x + 2] * z0[x + 1] +
                                  w1[2 * x] * z1[x] + w1[2 * x + 2] * z1[x + 1]);
        const float b2 = 0.25f * (w0[2 * x + 1] * z0[x] + w0[2 * x + 3] * z0[x + 1] +
                                  w1[2 * x + 1] * z1[x] + w1[2 * x + 3] * z1[x + 1]);
        float bgr[3];
        shader->Color(id, b1, b2, bgr);
        for (int k = 0; k < 3; ++k) {
          c0[3 * x + k] = c0[3 * x + 3 + k] = c1[3 * x + k] = c1[3 * x + 3 + k] = bgr[k];
        }
        continue;
      }
      shade(y, x);
      shade(y, x + 1);
      shade(y + 1, x);
      shade(y + 1, x + 1);
    }
    for (; x < width; ++x) {
      shade(y, x);
      shade(y + 1, x);
    }
  }
  for (; y < row_end; ++y) {
    for (int x = 0; x < width; ++x) shade(y, x);
  }
}

}  // namespace

void Render(const Mesh& mesh, const PinholeCamera& camera, const Rigid3d& cam_from_obj,
            const PixelRect& roi_in, const RenderOptions& options, RenderBuffers* out) {
  UNSEEN_CHECK(out != nullptr, "Render: output buffers are null");
  options.Check();
  camera.Check("Render camera");
  UNSEEN_CHECK(camera.width <= kMaxImageSide && camera.height <= kMaxImageSide,
               "Render camera: image size {}x{} exceeds {} px per side", camera.width,
               camera.height, kMaxImageSide);
  UNSEEN_CHECK(cam_from_obj.IsValid(), "Render: cam_from_obj is not a valid pose ({})",
               cam_from_obj.ToString());
  CheckMeshForRender(mesh);
  if (options.write_color) {
    const int nm = static_cast<int>(mesh.materials.size());
    for (size_t t = 0; t < mesh.triangle_materials.size(); ++t) {
      const int m = mesh.triangle_materials[t];
      UNSEEN_CHECK(m >= 0 && m < nm, "Render: mesh triangle {} has material {}, range is [0, {})",
                   t, m, nm);
    }
  }

  const PixelRect roi = roi_in.Intersect(camera.ImageRect());
  out->roi = roi;
  if (roi.empty()) {
    ReleaseOutputs(out);
    return;
  }

  // 1. Vertices to the camera frame, projected and snapped once.
  thread_local std::vector<ProjectedVertex> projected;
  const int nv = mesh.num_vertices();
  projected.resize(nv);
  {
    const Eigen::Matrix3f r = cam_from_obj.RotationMatrix().cast<float>();
    const Eigen::Vector3f tr = cam_from_obj.translation().cast<float>();
    const float fx = float(camera.fx), fy = float(camera.fy);
    const float cx = float(camera.cx), cy = float(camera.cy);
    const float near = float(options.near_m);
    const float lo_x = float(-kGuardPx), hi_x = float(camera.width + kGuardPx);
    const float lo_y = float(-kGuardPx), hi_y = float(camera.height + kGuardPx);
    const float scale = float(kSubpixel);
    float non_finite = 0.0f;  // stays 0 unless a coordinate is NaN or infinite
    for (int i = 0; i < nv; ++i) {
      const Eigen::Vector3f p = r * mesh.vertices[i] + tr;
      non_finite += 0.0f * (p.x() + p.y() + p.z());
      ProjectedVertex& q = projected[i];
      q.ok = 0;
      q.inv_z = 0.0f;
      if (p.z() >= near) {
        const float inv_z = 1.0f / p.z();
        const float u = fx * p.x() * inv_z + cx, v = fy * p.y() * inv_z + cy;
        if (u >= lo_x && u <= hi_x && v >= lo_y && v <= hi_y) {
          q.x = static_cast<int32_t>(std::lrintf(u * scale));
          q.y = static_cast<int32_t>(std::lrintf(v * scale));
          q.inv_z = inv_z;
          q.ok = 1;
        }
      }
    }
    if (non_finite != 0.0f) {
      for (int i = 0; i < nv; ++i) {
        const Eigen::Vector3f& v = mesh.vertices[i];
        UNSEEN_CHECK(v.allFinite(), "Render: mesh vertex {} is not finite ({} {} {})", i, v.x(),
                     v.y(), v.z());
      }
    }
  }

  // 2. Buffers: the z-buffer (1/z, 0 = empty) lives in `depth` until the resolve pass.
  const cv::Size size(roi.width(), roi.height());
  out->depth.create(size, CV_32FC1);
  out->depth.setTo(0.0f);
  out->mask.create(size, CV_8UC1);
  // Colour mode: texture coordinates interpolated directly when every material is
  // textured and each sample is shaded (one texture lookup per pixel, no per-triangle
  // work), else barycentric coordinates resolved per triangle.
  const bool uv_mode = options.write_color && !options.write_normals && !options.shade_quads &&
                       mesh.projectors.empty() &&
                       !mesh.uvs.empty() && !mesh.materials.empty() &&
                       std::all_of(mesh.materials.begin(), mesh.materials.end(),
                                   [](const Material& m) { return !m.texture.empty(); });
  const bool single_material = mesh.triangle_materials.empty() || mesh.materials.size() == 1;
  const bool need_weights = options.write_color || options.write_normals;
  const bool need_ids = (need_weights && !(uv_mode && single_material)) ||
                        options.write_triangle_ids;
  cv::Mat& ids = options.write_triangle_ids ? out->triangle_id : out->scratch_ids;
  if (need_ids) ids.create(size, CV_32SC1);
  if (!options.write_triangle_ids) out->triangle_id.release();
  if (need_weights) out->scratch_weights.create(size, CV_32FC2);

  RasterTarget target;
  target.roi = roi;
  target.inv_z = out->depth.ptr<float>();
  target.z_stride = out->depth.step1();
  if (need_ids) {
    target.ids = ids.ptr<int32_t>();
    target.id_stride = ids.step1();
  }
  if (need_weights) {
    target.weights = out->scratch_weights.ptr<float>();
    target.w_stride = out->scratch_weights.step1();
  }
  ClipContext clip;
  clip.rotation = cam_from_obj.RotationMatrix();
  clip.translation = cam_from_obj.translation();
  clip.fx = camera.fx;
  clip.fy = camera.fy;
  clip.cx = camera.cx;
  clip.cy = camera.cy;
  clip.lo_x = -kGuardPx;
  clip.hi_x = camera.width + kGuardPx;
  clip.lo_y = -kGuardPx;
  clip.hi_y = camera.height + kGuardPx;
  // Half-spaces n . p + d >= 0 in the camera frame (z > 0): z >= near; u >= lo_x is
  // fx x + (cx - lo_x) z >= 0; u <= hi_x is -fx x + (hi_x - cx) z >= 0; same for v.
  clip.planes[0] = {0.0, 0.0, 1.0, -options.near_m};
  clip.planes[1] = {camera.fx, 0.0, camera.cx - clip.lo_x, 0.0};
  clip.planes[2] = {-camera.fx, 0.0, clip.hi_x - camera.cx, 0.0};
  clip.planes[3] = {0.0, camera.fy, camera.cy - clip.lo_y, 0.0};
  clip.planes[4] = {0.0, -camera.fy, clip.hi_y - camera.cy, 0.0};

  // 3. Scan conversion.
  const bool cull = options.cull_back_faces;
  const Eigen::Vector2f* uvs = uv_mode ? mesh.uvs.data() : nullptr;
  TexelStats stats;
  const bool mipmaps = options.write_color && options.mipmaps && mesh.HasUvTexture();
  if (mipmaps) {
    for (const Material& m : mesh.materials) stats.texture_size.push_back(double(m.texture.total()));
    stats.texels.assign(mesh.materials.size(), 0.0);
    stats.pixels.assign(mesh.materials.size(), 0.0);
  }
  TexelStats* stats_ptr = mipmaps ? &stats : nullptr;
  if (need_weights && need_ids) {
    RasterMesh<true, true>(mesh, uvs, projected, cull, clip, target, stats_ptr);
  } else if (need_weights) {
    RasterMesh<true, false>(mesh, uvs, projected, cull, clip, target, stats_ptr);
  } else if (need_ids) {
    RasterMesh<false, true>(mesh, uvs, projected, cull, clip, target, stats_ptr);
  } else {
    RasterMesh<false, false>(mesh, uvs, projected, cull, clip, target, stats_ptr);
  }
  // The texture (level) of each material: one mip-map level per material and render,
  // from the mean number of texels per pixel of its drawn triangles.
  std::vector<cv::Mat> textures;
  for (size_t m = 0; m < mesh.materials.size(); ++m) {
    const cv::Mat& texture = mesh.materials[m].texture;
    textures.push_back(texture);
    if (!mipmaps || texture.empty() || !(stats.pixels[m] > 0.0)) continue;
    // Shaded once per 2x2 block, a sample stands for four pixels' texels.
    const double texels_per_pixel = stats.texels[m] * stats.texture_size[m] /
                                    (stats.pixels[m] / double(kSubpixel * kSubpixel)) *
                                    (options.shade_quads ? 4.0 : 1.0);
    if (MipmapLevelFor(texels_per_pixel, kMaxMipmapLevels) == 0) continue;
    const std::vector<cv::Mat> levels = MipmapLevels(texture);
    textures.back() = levels[MipmapLevelFor(texels_per_pixel, int(levels.size()))];
  }

  // 4. Resolve: metric depth, mask, ids, and colour/normals of the visible surface.
  if (options.write_color) {
    out->color.create(size, CV_32FC3);
  } else {
    out->color.release();
  }
  if (options.write_normals) {
    out->normal.create(size, CV_32FC3);
  } else {
    out->normal.release();
  }
  cv::compare(out->depth, 0.0f, out->mask, cv::CMP_GT);  // 255 where covered
  for (int y = 0; y < size.height; ++y) InvertPositive(out->depth.ptr<float>(y), size.width);
  const Eigen::Matrix3f rotation = cam_from_obj.RotationMatrix().cast<float>();
  const int width = size.width;
  // Rows are independent: bands of rows on the pool's threads, with a shader each (it
  // caches per-triangle state).
  const int bands = options.pool != nullptr && size.area() >= kParallelResolvePixels
                        ? std::min(options.pool->size(), size.height)
                        : 1;
  // Colour once per 2x2 block one triangle covers whole (bands of whole blocks).
  const bool quads = options.shade_quads && options.write_color;
  auto band_row = [&](int band) {
    return quads ? 2 * ((size.height / 2) * band / bands) + (band == bands ? size.height % 2 : 0)
                 : size.height * band / bands;
  };
  auto resolve_band = [&](int band) {
    Shader shader(mesh, textures);
    const int row_begin = band_row(band), row_end = band_row(band + 1);
    if (quads) ResolveQuadColors(*out, ids, row_begin, row_end, &shader);
    for (int y = row_begin; y < row_end; ++y) {
      float* z = out->depth.ptr<float>(y);
      uint8_t* m = out->mask.ptr<uint8_t>(y);
      if (options.write_triangle_ids) {
        int32_t* id = ids.ptr<int32_t>(y);
        for (int x = 0; x < width; ++x) id[x] = m[x] ? id[x] : -1;
      }
      if (options.write_color && !quads) {
        float* color = out->color.ptr<float>(y);
        const float* w = out->scratch_weights.ptr<float>(y);
        const int32_t* id = need_ids ? ids.ptr<int32_t>(y) : nullptr;
        if (uv_mode) {
          const TextureView* views = shader.textures();
          const std::vector<int>& materials = mesh.triangle_materials;
          for (int x = 0; x < width; ++x) {
            if (!m[x]) {
              color[3 * x] = color[3 * x + 1] = color[3 * x + 2] = 0.0f;
              continue;
            }
            const TextureView& texture = single_material ? views[0] : views[materials[id[x]]];
            SampleWrap(texture, w[2 * x] * z[x], w[2 * x + 1] * z[x], color + 3 * x);
          }
        } else {
          for (int x = 0; x < width; ++x) {
            if (!m[x]) {
              color[3 * x] = color[3 * x + 1] = color[3 * x + 2] = 0.0f;
              continue;
            }
            shader.Color(id[x], w[2 * x] * z[x], w[2 * x + 1] * z[x], color + 3 * x);
          }
        }
      }
      if (options.write_normals) {
        float* normal = out->normal.ptr<float>(y);
        const float* w = out->scratch_weights.ptr<float>(y);
        const int32_t* id = ids.ptr<int32_t>(y);
        std::memset(normal, 0, sizeof(float) * 3 * width);
        for (int x = 0; x < width; ++x) {
          if (!m[x]) continue;
          const Eigen::Vector3f n =
              rotation * shader.Normal(id[x], w[2 * x] * z[x], w[2 * x + 1] * z[x]);
          normal[3 * x] = n[0];
          normal[3 * x + 1] = n[1];
          normal[3 * x + 2] = n[2];
        }
      }
    }
  };
  if (bands > 1) {
    options.pool->ParallelFor(bands, resolve_band);
  } else {
    resolve_band(0);
  }
}

void PrepareForRendering(const Mesh& mesh) {
  if (!mesh.HasUvTexture()) return;
  for (const Material& m : mesh.materials) {
    if (!m.texture.empty()) MipmapLevels(m.texture);
  }
}

}  // namespace unseen
