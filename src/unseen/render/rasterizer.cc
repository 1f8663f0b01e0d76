// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/render/rasterizer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include <Eigen/Geometry>

#include "unseen/util/error.h"

namespace unseen {

void RenderOptions::Check() const {
  UNSEEN_CHECK(std::isfinite(near_m) && near_m > 0.0,
               "RenderOptions.near_m = {} must be positive and finite (metres)", near_m);
}

namespace {

constexpr int kSubpixelBits = 8;
constexpr int64_t kSubpixel = 1 << kSubpixelBits;  // screen positions snap to 1/256 px
constexpr double kGuardPx = 4096.0;  // triangles are clipped to the image grown by this
constexpr int kMaxImageSide = 32768;  // keeps snapped coordinates in int32
constexpr int kWideRowPx = 16;        // bounding boxes at least this wide skip to the span

// A mesh vertex after projection (one per vertex, shared by its triangles).
struct ProjectedVertex {
  int32_t x, y;  // pixel position * kSubpixel, rounded
  float inv_z;   // 1 / camera-frame z, 1/m
  int32_t ok;    // 1: z >= near and inside the guard band; 0: the triangle needs clipping
};

// A corner of a triangle handed to the scan converter: snapped position, 1/z, and the
// barycentric coordinates (b1, b2) of the point in its mesh triangle (the corners of an
// unclipped triangle are (0, 0), (1, 0), (0, 1)).
struct RasterVertex {
  int64_t x, y;
  float inv_z;
  float b1, b2;
};

// Where the scan converter writes; every pointer addresses image pixel (roi.x0, roi.y0).
struct RasterTarget {
  PixelRect roi;
  float* inv_z = nullptr;  // z-buffer of 1/z, 0 = empty
  size_t z_stride = 0;     // floats per row
  int32_t* ids = nullptr;
  size_t id_stride = 0;
  float* weights = nullptr;  // (b1/z, b2/z) per pixel
  size_t w_stride = 0;       // floats per row
};

inline int64_t FloorDiv(int64_t a, int64_t b) {  // b > 0
  const int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}
inline int64_t CeilDiv(int64_t a, int64_t b) { return -FloorDiv(-a, b); }

// Top-left rule with y down: an edge whose inward normal (a, b) points right (a > 0, a
// "left" edge) or, when horizontal, down (a "top" edge) owns the pixel centres on it.
inline int64_t FillBias(int64_t a, int64_t b) { return (a > 0 || (a == 0 && b > 0)) ? 0 : -1; }

// Affine screen-space interpolation f(x, y) = f0 + gx (x - x_ref) + gy (y - y_ref) of
// the corner values f0, f1, f2 (pixels).
struct Plane {
  float f0, gx, gy;
};

// Scan-converts one triangle. `cull`: drop it when it faces away from the camera.
// Front-facing triangles (counter-clockwise seen from outside) have negative signed area
// in y-down pixel coordinates.
template <bool kWeights, bool kIds>
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
  const int x_lo = static_cast<int>(std::max<int64_t>(t.roi.x0, CeilDiv(min_x, kSubpixel)));
  const int x_hi = static_cast<int>(std::min<int64_t>(t.roi.x1 - 1, FloorDiv(max_x, kSubpixel)));
  const int y_lo = static_cast<int>(std::max<int64_t>(t.roi.y0, CeilDiv(min_y, kSubpixel)));
  const int y_hi = static_cast<int>(std::min<int64_t>(t.roi.y1 - 1, FloorDiv(max_y, kSubpixel)));
  if (x_lo > x_hi || y_lo > y_hi) return;

  // Edge functions E_i = a_i x + b_i y + c_i (x, y in 1/256 px), E_i opposite v_i, positive
  // inside, E_i(v_i) = area2. Exact in 64 bits: |coordinates| < 2^24.
  const int64_t a0 = v1.y - v2.y, b0 = v2.x - v1.x;
  const int64_t a1 = v2.y - v0.y, b1 = v0.x - v2.x;
  const int64_t a2 = v0.y - v1.y, b2 = v1.x - v0.x;
  const int64_t px = x_lo * kSubpixel, py = y_lo * kSubpixel;
  int64_t e0_row = a0 * (px - v1.x) + b0 * (py - v1.y) + FillBias(a0, b0);
  int64_t e1_row = a1 * (px - v2.x) + b1 * (py - v2.y) + FillBias(a1, b1);
  int64_t e2_row = a2 * (px - v0.x) + b2 * (py - v0.y) + FillBias(a2, b2);
  const int64_t sx0 = a0 * kSubpixel, sx1 = a1 * kSubpixel, sx2 = a2 * kSubpixel;
  const int64_t sy0 = b0 * kSubpixel, sy1 = b1 * kSubpixel, sy2 = b2 * kSubpixel;

  // Barycentric l_k = E_k / area2; dl_k/dx = a_k * 256 / area2 per pixel.
  const double s = static_cast<double>(kSubpixel) / static_cast<double>(area2);
  const double l1x = a1 * s, l2x = a2 * s, l1y = b1 * s, l2y = b2 * s;
  auto make_plane = [&](double f0, double f1, double f2) {
    return Plane{static_cast<float>(f0), static_cast<float>(l1x * (f1 - f0) + l2x * (f2 - f0)),
                 static_cast<float>(l1y * (f1 - f0) + l2y * (f2 - f0))};
  };
  const float x_ref = static_cast<float>(v0.x) / kSubpixel;
  const float y_ref = static_cast<float>(v0.y) / kSubpixel;
  const Plane pz = make_plane(v0.inv_z, v1.inv_z, v2.inv_z);
  Plane pw1{}, pw2{};
  if constexpr (kWeights) {
    // b_k / z is affine in screen space (perspective-correct interpolation).
    pw1 = make_plane(double(v0.inv_z) * v0.b1, double(v1.inv_z) * v1.b1, double(v2.inv_z) * v2.b1);
    pw2 = make_plane(double(v0.inv_z) * v0.b2, double(v1.inv_z) * v1.b2, double(v2.inv_z) * v2.b2);
  }
  const bool wide = x_hi - x_lo >= kWideRowPx;

  for (int y = y_lo; y <= y_hi; ++y, e0_row += sy0, e1_row += sy1, e2_row += sy2) {
    int64_t e0 = e0_row, e1 = e1_row, e2 = e2_row;
    int x = x_lo;
    if (wide) {
      // Skip to (one pixel before) the first centre inside every edge rising with x; the
      // exact integer test below still decides each pixel.
      int64_t skip = 0;
      if (a0 > 0 && e0 < 0) skip = std::max(skip, int64_t(double(-e0) / double(sx0)) - 1);
      if (a1 > 0 && e1 < 0) skip = std::max(skip, int64_t(double(-e1) / double(sx1)) - 1);
      if (a2 > 0 && e2 < 0) skip = std::max(skip, int64_t(double(-e2) / double(sx2)) - 1);
      if (skip > x_hi - x) continue;
      x += static_cast<int>(skip);
      e0 += skip * sx0;
      e1 += skip * sx1;
      e2 += skip * sx2;
    }
    const float dy = static_cast<float>(y) - y_ref;
    const float z_row = pz.f0 + pz.gy * dy;
    float w1_row = 0.0f, w2_row = 0.0f;
    if constexpr (kWeights) {
      w1_row = pw1.f0 + pw1.gy * dy;
      w2_row = pw2.f0 + pw2.gy * dy;
    }
    float* z_ptr = t.inv_z + (y - t.roi.y0) * t.z_stride - t.roi.x0;
    int32_t* id_ptr = kIds ? t.ids + (y - t.roi.y0) * t.id_stride - t.roi.x0 : nullptr;
    float* w_ptr = kWeights ? t.weights + (y - t.roi.y0) * t.w_stride - 2 * t.roi.x0 : nullptr;
    bool entered = false;
    for (; x <= x_hi; ++x, e0 += sx0, e1 += sx1, e2 += sx2) {
      if ((e0 | e1 | e2) < 0) {
        if (entered) break;  // convex: the span has ended
        continue;
      }
      entered = true;
      const float dx = static_cast<float>(x) - x_ref;
      const float inv_z = z_row + pz.gx * dx;
      if (inv_z > z_ptr[x]) {
        z_ptr[x] = inv_z;
        if constexpr (kIds) id_ptr[x] = id;
        if constexpr (kWeights) {
          w_ptr[2 * x] = w1_row + pw1.gx * dx;
          w_ptr[2 * x + 1] = w2_row + pw2.gx * dx;
        }
      }
    }
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
template <bool kWeights, bool kIds>
void RasterClipped(const Mesh& mesh, const Eigen::Vector3i& tri, int32_t id, bool cull,
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
  for (int k = 0; k < n; ++k) {
    const ClipVertex& v = in[k];
    if (v.vertex >= 0 && projected[v.vertex].ok) {
      // Same snapped position as in the fast path, so shared edges stay watertight.
      const ProjectedVertex& q = projected[v.vertex];
      r[k] = {q.x, q.y, q.inv_z, float(v.b1), float(v.b2)};
      continue;
    }
    const double inv_z = 1.0 / v.p.z();
    const double u = std::clamp(c.fx * v.p.x() * inv_z + c.cx, c.lo_x, c.hi_x);
    const double w = std::clamp(c.fy * v.p.y() * inv_z + c.cy, c.lo_y, c.hi_y);
    r[k] = {std::llround(u * kSubpixel), std::llround(w * kSubpixel), float(inv_z), float(v.b1),
            float(v.b2)};
  }
  // The polygon keeps the triangle's orientation; culling was decided above.
  for (int k = 1; k + 1 < n; ++k) {
    RasterTriangle<kWeights, kIds>(r[0], r[k], r[k + 1], false, id, target);
  }
}

template <bool kWeights, bool kIds>
void RasterMesh(const Mesh& mesh, const std::vector<ProjectedVertex>& projected, bool cull,
                const ClipContext& clip, const RasterTarget& target) {
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
    if (p0.ok & p1.ok & p2.ok) {
      RasterTriangle<kWeights, kIds>({p0.x, p0.y, p0.inv_z, 0.0f, 0.0f},
                                     {p1.x, p1.y, p1.inv_z, 1.0f, 0.0f},
                                     {p2.x, p2.y, p2.inv_z, 0.0f, 1.0f}, cull, t, target);
    } else {
      RasterClipped<kWeights, kIds>(mesh, tri, t, cull, projected, clip, target);
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
  }
}

// Read-only view of a CV_32FC3 image.
struct TextureView {
  const float* data = nullptr;
  int width = 0, height = 0;
  size_t step = 0;  // floats per row
  explicit TextureView(const cv::Mat& m = cv::Mat()) {
    if (m.empty()) return;
    data = m.ptr<float>();
    width = m.cols;
    height = m.rows;
    step = m.step1();
  }
};

inline Eigen::Vector3f Lerp4(const float* p00, const float* p01, const float* p10,
                             const float* p11, float ax, float ay) {
  Eigen::Vector3f c;
  for (int k = 0; k < 3; ++k) {
    const float top = p00[k] + ax * (p01[k] - p00[k]);
    const float bottom = p10[k] + ax * (p11[k] - p10[k]);
    c[k] = top + ay * (bottom - top);
  }
  return c;
}

// Bilinear sample at OBJ texture coordinates (v up), repeating.
inline Eigen::Vector3f SampleWrap(const TextureView& t, float u, float v) {
  u -= std::floor(u);
  v -= std::floor(v);
  if (!(u >= 0.0f && u < 1.0f)) u = 0.0f;  // NaN uv
  if (!(v >= 0.0f && v < 1.0f)) v = 0.0f;
  const float fx = u * t.width - 0.5f, fy = (1.0f - v) * t.height - 0.5f;
  const float flx = std::floor(fx), fly = std::floor(fy);
  int x0 = static_cast<int>(flx), y0 = static_cast<int>(fly);  // in [-1, size - 1]
  int x1 = x0 + 1, y1 = y0 + 1;
  if (x0 < 0) x0 = t.width - 1;
  if (x1 >= t.width) x1 = 0;
  if (y0 < 0) y0 = t.height - 1;
  if (y1 >= t.height) y1 = 0;
  const float* r0 = t.data + y0 * t.step;
  const float* r1 = t.data + y1 * t.step;
  return Lerp4(r0 + 3 * x0, r0 + 3 * x1, r1 + 3 * x0, r1 + 3 * x1, fx - flx, fy - fly);
}

// Bilinear sample at a pixel position (pixel-centre convention), clamped to the image.
inline Eigen::Vector3f SampleClamp(const TextureView& t, float x, float y) {
  x = std::clamp(x, 0.0f, static_cast<float>(t.width - 1));
  y = std::clamp(y, 0.0f, static_cast<float>(t.height - 1));
  const int x0 = std::min(static_cast<int>(x), t.width - 1);
  const int y0 = std::min(static_cast<int>(y), t.height - 1);
  const int x1 = std::min(x0 + 1, t.width - 1), y1 = std::min(y0 + 1, t.height - 1);
  const float* r0 = t.data + y0 * t.step;
  const float* r1 = t.data + y1 * t.step;
  return Lerp4(r0 + 3 * x0, r0 + 3 * x1, r1 + 3 * x0, r1 + 3 * x1, x - x0, y - y0);
}

struct ProjectorView {
  Eigen::Matrix3f rotation;
  Eigen::Vector3f translation;
  float fx, fy, cx, cy;
  float max_x, max_y;  // width - 0.5, height - 0.5
  TextureView image;
};

// Colour of the surface point with barycentric coordinates (b1, b2) in triangle `tri`.
class Shader {
 public:
  explicit Shader(const Mesh& mesh) : mesh_(mesh) {
    textures_.reserve(mesh.materials.size());
    for (const Material& m : mesh.materials) textures_.emplace_back(m.texture);
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
      projectors_.push_back(v);
    }
  }

  Eigen::Vector3f Color(int tri, float b1, float b2) const {
    const Eigen::Vector3i& t = mesh_.triangles[tri];
    if (!projectors_.empty()) {
      Eigen::Vector3f c;
      if (ProjectiveColor(t, b1, b2, &c)) return c;
    }
    const int m = mesh_.triangle_materials.empty() ? (mesh_.materials.empty() ? -1 : 0)
                                                   : mesh_.triangle_materials[tri];
    if (m >= 0 && textures_[m].data != nullptr && !mesh_.uvs.empty()) {
      const Eigen::Vector2f& u0 = mesh_.uvs[t[0]];
      const Eigen::Vector2f uv = u0 + b1 * (mesh_.uvs[t[1]] - u0) + b2 * (mesh_.uvs[t[2]] - u0);
      return SampleWrap(textures_[m], uv.x(), uv.y());
    }
    if (!mesh_.colors_bgr.empty()) {
      const Eigen::Vector3f& c0 = mesh_.colors_bgr[t[0]];
      return c0 + b1 * (mesh_.colors_bgr[t[1]] - c0) + b2 * (mesh_.colors_bgr[t[2]] - c0);
    }
    if (m >= 0) return mesh_.materials[m].diffuse_bgr;
    return Eigen::Vector3f::Ones();
  }

  // Unit normal in the object frame.
  Eigen::Vector3f Normal(int tri, float b1, float b2) const {
    const Eigen::Vector3i& t = mesh_.triangles[tri];
    Eigen::Vector3f n;
    if (!mesh_.normals.empty()) {
      const Eigen::Vector3f& n0 = mesh_.normals[t[0]];
      n = n0 + b1 * (mesh_.normals[t[1]] - n0) + b2 * (mesh_.normals[t[2]] - n0);
    } else {
      const Eigen::Vector3f& v0 = mesh_.vertices[t[0]];
      n = (mesh_.vertices[t[1]] - v0).cross(mesh_.vertices[t[2]] - v0);
    }
    const float len = n.norm();
    return len > 0.0f ? Eigen::Vector3f(n / len) : Eigen::Vector3f::Zero();
  }

 private:
  bool ProjectiveColor(const Eigen::Vector3i& t, float b1, float b2, Eigen::Vector3f* c) const {
    const Eigen::Vector3f& v0 = mesh_.vertices[t[0]];
    const Eigen::Vector3f e1 = mesh_.vertices[t[1]] - v0, e2 = mesh_.vertices[t[2]] - v0;
    const Eigen::Vector3f p = v0 + b1 * e1 + b2 * e2;
    const Eigen::Vector3f n = e1.cross(e2);
    int best = -1;
    float best_score = 0.0f, best_x = 0.0f, best_y = 0.0f;
    for (size_t k = 0; k < projectors_.size(); ++k) {
      const ProjectorView& v = projectors_[k];
      const Eigen::Vector3f q = v.rotation * p + v.translation;
      if (!(q.z() > 0.0f)) continue;
      const float x = v.fx * q.x() / q.z() + v.cx, y = v.fy * q.y() / q.z() + v.cy;
      if (!(x >= -0.5f && y >= -0.5f && x < v.max_x && y < v.max_y)) continue;
      // Cosine (times |n|) between the normal and the direction to the projector.
      const float score = -(v.rotation * n).dot(q) / q.norm();
      if (score > best_score) {
        best = static_cast<int>(k);
        best_score = score;
        best_x = x;
        best_y = y;
      }
    }
    if (best < 0) return false;
    *c = SampleClamp(projectors_[best].image, best_x, best_y);
    return true;
  }

  const Mesh& mesh_;
  std::vector<TextureView> textures_;
  std::vector<ProjectorView> projectors_;
};

void ReleaseOutputs(RenderBuffers* out) {
  out->color.release();
  out->depth.release();
  out->mask.release();
  out->triangle_id.release();
  out->normal.release();
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
  const bool need_weights = options.write_color || options.write_normals;
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
  const bool need_ids = need_weights || options.write_triangle_ids;
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
  if (need_weights) {
    RasterMesh<true, true>(mesh, projected, cull, clip, target);
  } else if (need_ids) {
    RasterMesh<false, true>(mesh, projected, cull, clip, target);
  } else {
    RasterMesh<false, false>(mesh, projected, cull, clip, target);
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
  if (!need_ids) {
    for (int y = 0; y < size.height; ++y) {
      float* z = out->depth.ptr<float>(y);
      uint8_t* m = out->mask.ptr<uint8_t>(y);
      for (int x = 0; x < size.width; ++x) {
        const bool covered = z[x] > 0.0f;
        m[x] = covered ? 255 : 0;
        z[x] = covered ? 1.0f / z[x] : 0.0f;
      }
    }
    return;
  }
  const Shader shader(mesh);
  const Eigen::Matrix3f rotation = cam_from_obj.RotationMatrix().cast<float>();
  for (int y = 0; y < size.height; ++y) {
    float* z = out->depth.ptr<float>(y);
    uint8_t* m = out->mask.ptr<uint8_t>(y);
    int32_t* id = ids.ptr<int32_t>(y);
    const float* w = need_weights ? out->scratch_weights.ptr<float>(y) : nullptr;
    float* color = options.write_color ? out->color.ptr<float>(y) : nullptr;
    float* normal = options.write_normals ? out->normal.ptr<float>(y) : nullptr;
    for (int x = 0; x < size.width; ++x) {
      if (!(z[x] > 0.0f)) {
        z[x] = 0.0f;
        m[x] = 0;
        id[x] = -1;
        if (color) color[3 * x] = color[3 * x + 1] = color[3 * x + 2] = 0.0f;
        if (normal) normal[3 * x] = normal[3 * x + 1] = normal[3 * x + 2] = 0.0f;
        continue;
      }
      const float depth = 1.0f / z[x];
      z[x] = depth;
      m[x] = 255;
      if (!need_weights) continue;
      const float b1 = w[2 * x] * depth, b2 = w[2 * x + 1] * depth;
      if (color) {
        const Eigen::Vector3f c = shader.Color(id[x], b1, b2);
        color[3 * x] = c[0];
        color[3 * x + 1] = c[1];
        color[3 * x + 2] = c[2];
      }
      if (normal) {
        const Eigen::Vector3f n = rotation * shader.Normal(id[x], b1, b2);
        normal[3 * x] = n[0];
        normal[3 * x + 1] = n[1];
        normal[3 * x + 2] = n[2];
      }
    }
  }
}

}  // namespace unseen
