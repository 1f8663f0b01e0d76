// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/mesh/primitives.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "unseen/image/image_io.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Converts an 8-bit BGR drawing to the in-memory texture format (CV_32FC3 in [0, 1]).
cv::Mat ToTexture(const cv::Mat& bgr8) {
  cv::Mat out;
  bgr8.convertTo(out, CV_32FC3, 1.0 / 255.0);
  return out;
}

// Appends one planar rectangular face with its own four vertices, uv square [0, 1]^2 and
// material `material`. The face lies at `normal * offset` and spans `width` along
// right = up x normal (texture u) and `height` along `up` (texture v). Since
// right x up = normal, the triangles are counter-clockwise seen from outside.
void AddFace(const Eigen::Vector3f& normal, const Eigen::Vector3f& up, float offset, float width,
             float height, int material, Mesh* mesh) {
  const Eigen::Vector3f right = up.cross(normal);
  const Eigen::Vector3f centre = normal * offset;
  const int base = mesh->num_vertices();
  const float corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (const auto& c : corners) {
    mesh->vertices.push_back(centre + (c[0] - 0.5f) * width * right + (c[1] - 0.5f) * height * up);
    mesh->uvs.emplace_back(c[0], c[1]);
    mesh->normals.push_back(normal);
  }
  mesh->triangles.emplace_back(base, base + 1, base + 2);
  mesh->triangles.emplace_back(base, base + 2, base + 3);
  mesh->triangle_materials.push_back(material);
  mesh->triangle_materials.push_back(material);
}

// The six faces of an axis-aligned box in the order +x, -x, +y, -y, +z, -z: outward normal
// and the "up" direction of the face's texture (z for the side faces, y for the top and
// bottom), so that textures read upright when the box stands on -z.
struct FaceFrame {
  Eigen::Vector3f normal;
  Eigen::Vector3f up;
  int normal_axis;
  int right_axis;
  int up_axis;
};
const FaceFrame kBoxFaces[6] = {
    {{1, 0, 0}, {0, 0, 1}, 0, 1, 2}, {{-1, 0, 0}, {0, 0, 1}, 0, 1, 2},
    {{0, 1, 0}, {0, 0, 1}, 1, 0, 2}, {{0, -1, 0}, {0, 0, 1}, 1, 0, 2},
    {{0, 0, 1}, {0, 1, 0}, 2, 0, 1}, {{0, 0, -1}, {0, 1, 0}, 2, 0, 1},
};
const char* const kBoxFaceNames[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
const char* const kBoxFaceFiles[6] = {"px", "mx", "py", "my", "pz", "mz"};

// Builds a box mesh of the given size with one material per face.
Mesh MakeBoxGeometry(const Eigen::Vector3f& size, std::vector<Material> materials) {
  Mesh mesh;
  for (int f = 0; f < 6; ++f) {
    const FaceFrame& face = kBoxFaces[f];
    AddFace(face.normal, face.up, 0.5f * size[face.normal_axis], size[face.right_axis],
            size[face.up_axis], f, &mesh);
  }
  mesh.materials = std::move(materials);
  return mesh;
}

// Draws `text` centred on `centre_y` (pixel row) in `image`, as large as fits in `fill` of
// the image width and `fill_height` of its height.
void PutCentredText(const std::string& text, double fill, double fill_height, int centre_y,
                    const cv::Scalar& colour, cv::Mat* image) {
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  int baseline = 0;
  const cv::Size unit = cv::getTextSize(text, font, 1.0, 1, &baseline);
  const double scale = std::min(fill * image->cols / std::max(1, unit.width),
                                fill_height * image->rows / std::max(1, unit.height));
  const int thickness = std::max(1, static_cast<int>(std::lround(scale * 2.5)));
  const cv::Size size = cv::getTextSize(text, font, scale, thickness, &baseline);
  const cv::Point origin((image->cols - size.width) / 2, centre_y + size.height / 2);
  cv::putText(*image, text, origin, font, scale, colour, thickness, cv::LINE_AA);
}

// An irregular closed blob: a polygon around `centre` whose radius varies smoothly with
// the angle (a few random harmonics), as a star-shaped "continent".
std::vector<cv::Point> MakeBlob(cv::RNG& rng, const cv::Point2d& centre, double radius,
                                double aspect) {
  constexpr int kHarmonics = 5;
  double amp[kHarmonics], phase[kHarmonics];
  for (int h = 0; h < kHarmonics; ++h) {
    amp[h] = rng.uniform(0.0, 0.35 / (h + 1));
    phase[h] = rng.uniform(0.0, 2.0 * kPi);
  }
  std::vector<cv::Point> polygon;
  constexpr int kPoints = 96;
  for (int i = 0; i < kPoints; ++i) {
    const double a = 2.0 * kPi * i / kPoints;
    double r = 1.0;
    for (int h = 0; h < kHarmonics; ++h) r += amp[h] * std::sin((h + 2) * a + phase[h]);
    r = std::max(0.25, r) * radius;
    polygon.emplace_back(static_cast<int>(std::lround(centre.x + r * aspect * std::cos(a))),
                         static_cast<int>(std::lround(centre.y + r * std::sin(a))));
  }
  return polygon;
}

// Adds smooth low-frequency shading (+-amplitude) so that no region of a generated texture
// is perfectly flat: random coarse grid, up-sampled bicubically. Wraps horizontally when
// `wrap_x` (for equirectangular images).
void AddSmoothNoise(cv::RNG& rng, int cells_x, int cells_y, double amplitude, bool wrap_x,
                    cv::Mat* image8) {
  cv::Mat coarse(cells_y + 1, cells_x + 1, CV_32FC1);
  rng.fill(coarse, cv::RNG::UNIFORM, -amplitude, amplitude);
  if (wrap_x) coarse.col(0).copyTo(coarse.col(cells_x));
  cv::Mat fine;
  cv::resize(coarse, fine, image8->size(), 0, 0, cv::INTER_CUBIC);
  cv::Mat as_float;
  image8->convertTo(as_float, CV_32FC3);
  cv::Mat fine3;
  cv::merge(std::vector<cv::Mat>{fine, fine, fine}, fine3);
  as_float += fine3;
  as_float.convertTo(*image8, CV_8UC3);  // saturates to [0, 255]
}

// Generated texture of one box face; `kind` (0..5) picks the pattern.
cv::Mat MakeBoxFaceTexture(int kind, int width, int height) {
  cv::RNG rng(1000 + kind);
  cv::Mat img;
  const int s = std::min(width, height);
  switch (kind) {
    case 0: {  // diagonal colour stripes
      img.create(height, width, CV_8UC3);
      const cv::Vec3b colours[3] = {{30, 30, 200}, {240, 240, 240}, {40, 150, 40}};
      const int period = std::max(6, s / 8);
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) img.at<cv::Vec3b>(y, x) = colours[((x + y) / period) % 3];
      }
      break;
    }
    case 1: {  // checker board with a coloured disc
      img.create(height, width, CV_8UC3);
      const int period = std::max(4, s / 6);
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
          const bool black = ((x / period) + (y / period)) % 2 == 0;
          img.at<cv::Vec3b>(y, x) = black ? cv::Vec3b(20, 20, 20) : cv::Vec3b(230, 230, 230);
        }
      }
      cv::circle(img, {width / 2, height / 2}, s / 4, {0, 140, 255}, cv::FILLED, cv::LINE_AA);
      break;
    }
    case 2: {  // text on yellow
      img.create(height, width, CV_8UC3);
      img.setTo(cv::Scalar(40, 210, 240));
      PutCentredText("unseen", 0.8, 0.35, height / 3, {60, 20, 20}, &img);
      PutCentredText("6-DoF", 0.6, 0.25, height * 3 / 4, {0, 0, 170}, &img);
      const int period = std::max(4, s / 10);
      for (int y = period / 2; y < height; y += period) {
        cv::line(img, {0, y}, {width / 8, y}, {0, 0, 160}, std::max(1, s / 64));
      }
      break;
    }
    case 3: {  // coloured blobs on teal
      img.create(height, width, CV_8UC3);
      img.setTo(cv::Scalar(150, 130, 20));
      for (int b = 0; b < 9; ++b) {
        const cv::Point2d c(rng.uniform(0.0, double(width)), rng.uniform(0.0, double(height)));
        const auto blob = MakeBlob(rng, c, rng.uniform(0.08, 0.2) * s, 1.0);
        const cv::Scalar colour(rng.uniform(0, 256), rng.uniform(0, 256), rng.uniform(0, 256));
        cv::fillPoly(img, std::vector<std::vector<cv::Point>>{blob}, colour, cv::LINE_AA);
      }
      break;
    }
    case 4: {  // concentric rings (red / white) with a cross
      img.create(height, width, CV_8UC3);
      const int period = std::max(4, s / 10);
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
          const double r = std::hypot(x - 0.5 * width, y - 0.5 * height);
          img.at<cv::Vec3b>(y, x) = (static_cast<int>(r) / period) % 2 == 0
                                        ? cv::Vec3b(40, 40, 210)
                                        : cv::Vec3b(235, 235, 235);
        }
      }
      cv::line(img, {0, height / 2}, {width, height / 2}, {20, 20, 20}, std::max(1, s / 40));
      cv::line(img, {width / 2, 0}, {width / 2, height}, {20, 20, 20}, std::max(1, s / 40));
      break;
    }
    default: {  // grid of dots and a triangle on violet
      img.create(height, width, CV_8UC3);
      img.setTo(cv::Scalar(160, 60, 120));
      const int period = std::max(6, s / 6);
      for (int y = period / 2; y < height; y += period) {
        for (int x = period / 2; x < width; x += period) {
          cv::circle(img, {x, y}, std::max(2, period / 4), {200, 255, 200}, cv::FILLED,
                     cv::LINE_AA);
        }
      }
      const std::vector<cv::Point> tri = {
          {width / 5, height * 4 / 5}, {width * 4 / 5, height * 4 / 5}, {width / 2, height / 5}};
      cv::fillPoly(img, std::vector<std::vector<cv::Point>>{tri}, {0, 200, 255}, cv::LINE_AA);
      break;
    }
  }
  AddSmoothNoise(rng, 8, 8, 12.0, false, &img);
  return ToTexture(img);
}

// The default equirectangular globe: ocean with smooth shading, irregular continents of
// several colours (wrapping around the seam), polar caps, meridians and parallels.
cv::Mat MakeGlobeTexture(int width, int height) {
  cv::RNG rng(20240611);
  cv::Mat img(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {  // ocean, darker towards the poles
    const double lat = std::abs(0.5 - (y + 0.5) / height) * 2.0;
    const cv::Vec3b ocean(static_cast<uchar>(190 - 70 * lat), static_cast<uchar>(110 - 40 * lat),
                          static_cast<uchar>(30 + 10 * lat));
    for (int x = 0; x < width; ++x) img.at<cv::Vec3b>(y, x) = ocean;
  }
  const cv::Scalar land_colours[] = {{40, 150, 50},  {70, 170, 200}, {30, 90, 110},
                                     {60, 200, 120}, {90, 120, 160}, {20, 110, 30}};
  constexpr int kContinents = 9;
  for (int c = 0; c < kContinents; ++c) {
    const cv::Point2d centre(rng.uniform(0.0, double(width)),
                             rng.uniform(0.2 * height, 0.8 * height));
    const double radius = rng.uniform(0.06, 0.14) * height;
    const auto blob = MakeBlob(rng, centre, radius, rng.uniform(1.0, 2.2));
    const cv::Scalar colour = land_colours[c % 6];
    // A smaller inner blob of another colour gives the continent internal structure.
    const auto inner = MakeBlob(rng, centre, 0.45 * radius, 1.3);
    const cv::Scalar inner_colour = land_colours[(c + 3) % 6];
    for (int shift : {-width, 0, width}) {  // wrap around the u = 0/1 seam
      auto moved = blob;
      auto moved_inner = inner;
      for (cv::Point& p : moved) p.x += shift;
      for (cv::Point& p : moved_inner) p.x += shift;
      cv::fillPoly(img, std::vector<std::vector<cv::Point>>{moved}, colour, cv::LINE_AA);
      cv::fillPoly(img, std::vector<std::vector<cv::Point>>{moved_inner}, inner_colour,
                   cv::LINE_AA);
    }
  }
  // Polar caps with a ragged edge.
  for (int x = 0; x < width; x += 4) {
    const int north = static_cast<int>(0.05 * height + rng.uniform(0.0, 0.03 * height));
    const int south = static_cast<int>(0.05 * height + rng.uniform(0.0, 0.03 * height));
    cv::rectangle(img, {x, 0}, {x + 4, north}, {235, 235, 235}, cv::FILLED);
    cv::rectangle(img, {x, height - south}, {x + 4, height}, {235, 235, 235}, cv::FILLED);
  }
  AddSmoothNoise(rng, 32, 16, 18.0, true, &img);
  // Graticule: 8 meridians and 5 parallels in dark grey.
  const int thickness = std::max(1, height / 256);
  for (int m = 0; m < 8; ++m) {
    const int x = m * width / 8;
    cv::line(img, {x, 0}, {x, height - 1}, {50, 50, 50}, thickness);
  }
  for (int p = 1; p <= 5; ++p) {
    const int y = p * height / 6;
    cv::line(img, {0, y}, {width - 1, y}, {50, 50, 50}, thickness);
  }
  return ToTexture(img);
}

}  // namespace

Mesh MakeLetteredCube(double edge_m, int texture_px) {
  UNSEEN_CHECK(std::isfinite(edge_m) && edge_m > 0.0,
               "MakeLetteredCube: edge_m must be positive and finite, got {}", edge_m);
  UNSEEN_CHECK(texture_px >= 16 && texture_px <= 8192,
               "MakeLetteredCube: texture_px must be in [16, 8192], got {}", texture_px);
  // Saturated, well separated background colours (BGR) and a contrasting letter colour.
  const cv::Scalar backgrounds[6] = {{0, 0, 220},   {0, 200, 0},   {220, 60, 0},
                                     {0, 220, 230}, {220, 0, 200}, {230, 200, 0}};
  const bool white_letter[6] = {true, true, true, false, true, false};
  std::vector<Material> materials;
  for (int f = 0; f < 6; ++f) {
    const std::string letter(1, static_cast<char>('A' + f));
    cv::Mat img(texture_px, texture_px, CV_8UC3, backgrounds[f]);
    const cv::Scalar ink = white_letter[f] ? cv::Scalar(255, 255, 255) : cv::Scalar(0, 0, 0);
    PutCentredText(letter, 0.7, 0.65, texture_px / 2, ink, &img);
    // A contrasting frame just inside the border marks the face edges.
    const int inset = texture_px / 16;
    cv::rectangle(img, {inset, inset}, {texture_px - 1 - inset, texture_px - 1 - inset}, ink,
                  std::max(1, texture_px / 64));
    Material m;
    m.name = "face_" + letter;
    m.texture = ToTexture(img);
    m.texture_path = "face_" + letter + ".png";
    materials.push_back(std::move(m));
  }
  const float e = static_cast<float>(edge_m);
  return MakeBoxGeometry(Eigen::Vector3f(e, e, e), std::move(materials));
}

Mesh MakeTexturedSphere(double radius_m, int rings, int segments, const cv::Mat& texture) {
  UNSEEN_CHECK(std::isfinite(radius_m) && radius_m > 0.0,
               "MakeTexturedSphere: radius_m must be positive and finite, got {}", radius_m);
  UNSEEN_CHECK(rings >= 2, "MakeTexturedSphere: rings must be >= 2, got {}", rings);
  UNSEEN_CHECK(segments >= 3, "MakeTexturedSphere: segments must be >= 3, got {}", segments);
  UNSEEN_CHECK(static_cast<long>(rings + 1) * (segments + 1) < (1L << 30),
               "MakeTexturedSphere: {} rings x {} segments is too many", rings, segments);
  Mesh mesh;
  const float r = static_cast<float>(radius_m);
  // Grid of (rings + 1) x (segments + 1) vertices; the last column repeats the first with
  // u = 1 (texture seam); theta from the north pole (+z), phi around z from +x.
  for (int i = 0; i <= rings; ++i) {
    const double theta = kPi * i / rings;
    for (int j = 0; j <= segments; ++j) {
      const double phi = 2.0 * kPi * j / segments;
      const Eigen::Vector3f n(static_cast<float>(std::sin(theta) * std::cos(phi)),
                              static_cast<float>(std::sin(theta) * std::sin(phi)),
                              static_cast<float>(std::cos(theta)));
      mesh.vertices.push_back(r * n);
      mesh.normals.push_back(n);
      // At the poles, u in the middle of the segment keeps the texture undistorted.
      const bool pole = i == 0 || i == rings;
      const double u = pole ? std::min(1.0, (j + 0.5) / segments) : double(j) / segments;
      mesh.uvs.emplace_back(static_cast<float>(u), static_cast<float>(1.0 - double(i) / rings));
    }
  }
  const int stride = segments + 1;
  for (int i = 0; i < rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      const int a = i * stride + j;        // (i, j)
      const int b = (i + 1) * stride + j;  // one ring south
      const int c = b + 1;
      const int d = a + 1;
      // (a, b, c) is counter-clockwise seen from outside (south x east = outward).
      if (i != rings - 1) mesh.triangles.emplace_back(a, b, c);  // b == c at the south pole
      if (i != 0) mesh.triangles.emplace_back(a, c, d);          // a == d at the north pole
    }
  }
  Material m;
  m.name = "sphere";
  m.texture_path = "sphere.png";
  m.texture = texture.empty() ? MakeGlobeTexture(1024, 512)
                              : ToFloatBgr(texture, "MakeTexturedSphere texture");
  mesh.materials.push_back(std::move(m));
  mesh.triangle_materials.assign(mesh.triangles.size(), 0);
  return mesh;
}

Mesh MakeTexturedBox(const Eigen::Vector3d& size_m, const std::array<cv::Mat, 6>& face_textures) {
  UNSEEN_CHECK(size_m.allFinite() && (size_m.array() > 0.0).all(),
               "MakeTexturedBox: size_m must be positive and finite, got ({} {} {})", size_m.x(),
               size_m.y(), size_m.z());
  const Eigen::Vector3f size = size_m.cast<float>();
  std::vector<Material> materials;
  for (int f = 0; f < 6; ++f) {
    Material m;
    m.name = std::string("face_") + kBoxFaceNames[f];
    m.texture_path = std::string("box_") + kBoxFaceFiles[f] + ".png";
    if (!face_textures[f].empty()) {
      m.texture = ToFloatBgr(face_textures[f],
                             std::string("MakeTexturedBox texture of face ") + kBoxFaceNames[f]);
    } else {
      // Keep the face's aspect ratio: 256 px along its longer side.
      const float w = size[kBoxFaces[f].right_axis];
      const float h = size[kBoxFaces[f].up_axis];
      const float px_per_m = 256.0f / std::max(w, h);
      m.texture = MakeBoxFaceTexture(f, std::max(16, static_cast<int>(std::lround(w * px_per_m))),
                                     std::max(16, static_cast<int>(std::lround(h * px_per_m))));
    }
    materials.push_back(std::move(m));
  }
  return MakeBoxGeometry(size, std::move(materials));
}

}  // namespace unseen
