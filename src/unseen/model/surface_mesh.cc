// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/surface_mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <unordered_map>
#include <vector>

#include "unseen/track/live_appearance.h"
#include "unseen/util/error.h"

namespace unseen {


namespace {

// Where a pixel is a 3x3 local maximum of `m` (CV_32FC1).
cv::Mat LocalMaxima(const cv::Mat& m) {
  cv::Mat dilated;
  cv::dilate(m, dilated, cv::Mat::ones(3, 3, CV_8U));
  return m >= dilated;
}

struct Vertex {
  int x = 0, y = 0;
  Eigen::Vector3d in_cam;
};

}  // namespace

std::optional<Mesh> BuildSurfaceMesh(const DepthMap& depth_map, const cv::Mat& image,
                                     const PinholeCamera& camera, const Rigid3d& cam_from_obj,
                                     const cv::Mat& mask, const SurfaceMeshOptions& options,
                                     SurfaceMeshReport* report, std::string* why) {
  options.Check();
  const cv::Size size(camera.width, camera.height);
  UNSEEN_CHECK(depth_map.depth.type() == CV_32FC1 && depth_map.depth.size() == size,
               "BuildSurfaceMesh: depth map is {}x{} type {}; expected {}x{} CV_32FC1",
               depth_map.depth.cols, depth_map.depth.rows, depth_map.depth.type(), size.width,
               size.height);
  UNSEEN_CHECK(image.type() == CV_32FC3 && image.size() == size,
               "BuildSurfaceMesh: image is {}x{} type {}; expected {}x{} CV_32FC3", image.cols,
               image.rows, image.type(), size.width, size.height);
  UNSEEN_CHECK(mask.type() == CV_8UC1 && mask.size() == size,
               "BuildSurfaceMesh: mask is {}x{} type {}; expected {}x{} CV_8UC1", mask.cols,
               mask.rows, mask.type(), size.width, size.height);
  SurfaceMeshReport local_report;
  SurfaceMeshReport& rep = report ? *report : local_report;
  rep = SurfaceMeshReport();
  auto fail = [&](const std::string& reason) -> std::optional<Mesh> {
    if (why) *why = reason;
    return std::nullopt;
  };
  const cv::Rect region = cv::boundingRect(mask);
  if (region.area() == 0) return fail("the object's mask is empty");

  cv::Mat depth = depth_map.depth;
  if (options.median_px > 1) cv::medianBlur(depth_map.depth, depth, options.median_px);
  const cv::Mat texturedness =
      depth_map.texturedness.size() == size ? depth_map.texturedness : Texturedness(image);
  const cv::Mat texture_peak = LocalMaxima(texturedness);
  // Harris corners over the region (grown for the window), thresholded by the region's
  // strongest response inside the mask.
  const cv::Rect grown = cv::Rect(region.x - 3, region.y - 3, region.width + 6, region.height + 6) &
                         cv::Rect(0, 0, size.width, size.height);
  cv::Mat grey, harris;
  cv::cvtColor(image(grown), grey, cv::COLOR_BGR2GRAY);
  cv::cornerHarris(grey, harris, 3, 3, options.harris_k, cv::BORDER_REPLICATE);
  double strongest = 0.0;
  cv::minMaxLoc(harris, nullptr, &strongest, nullptr, nullptr, mask(grown));
  const float corner_threshold = static_cast<float>(options.harris_quality * strongest);
  const cv::Mat corner_peak = LocalMaxima(harris);

  // Step 3: one vertex per grid box.
  const float min_t = static_cast<float>(options.min_texturedness);
  const int cell = options.cell_px;
  const Rigid3d obj_from_cam = cam_from_obj.Inverse();
  std::vector<Vertex> vertices;
  for (int by = region.y; by < region.y + region.height; by += cell) {
    for (int bx = region.x; bx < region.x + region.width; bx += cell) {
      const int ex = std::min(bx + cell, region.x + region.width);
      const int ey = std::min(by + cell, region.y + region.height);
      const double cx = 0.5 * (bx + ex - 1), cy = 0.5 * (by + ey - 1);
      int corner = -1, textured = -1, plain = -1;
      float best_corner = corner_threshold;
      double textured_d2 = std::numeric_limits<double>::infinity(), plain_d2 = textured_d2;
      for (int y = by; y < ey; ++y) {
        for (int x = bx; x < ex; ++x) {
          if (!mask.at<uint8_t>(y, x) || !(depth.at<float>(y, x) > 0.0f)) continue;
          const int key = y * size.width + x;
          const float h = harris.at<float>(y - grown.y, x - grown.x);
          if (h > best_corner && corner_peak.at<uint8_t>(y - grown.y, x - grown.x)) {
            best_corner = h;
            corner = key;
          }
          const double d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
          if (texturedness.at<float>(y, x) >= min_t && texture_peak.at<uint8_t>(y, x) &&
              d2 < textured_d2) {
            textured_d2 = d2;
            textured = key;
          }
          if (options.untextured_vertices && d2 < plain_d2) {
            plain_d2 = d2;
            plain = key;
          }
        }
      }
      const int chosen = corner >= 0 ? corner : textured >= 0 ? textured : plain;
      if (chosen < 0) continue;
      ++rep.candidate_vertices;
      Vertex v;
      v.x = chosen % size.width;
      v.y = chosen / size.width;
      v.in_cam = camera.Unproject(Eigen::Vector2d(v.x, v.y), depth.at<float>(v.y, v.x));
      // Step 5: the object's extent around its origin.
      if (options.max_radius_m > 0.0 && (obj_from_cam * v.in_cam).norm() > options.max_radius_m) {
        ++rep.dropped_far;
        continue;
      }
      vertices.push_back(v);
    }
  }
  // Beyond the thesis: vertices along the outline (2 px inside it, clear of mixed depth),
  // every cell_px, so that the mesh reaches the silhouette the tracker aligns.
  if (options.contour_vertices) {
    cv::Mat inner;
    cv::erode(mask, inner, cv::Mat::ones(5, 5, CV_8U));
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(inner, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
    for (const std::vector<cv::Point>& contour : contours) {
      int since = cell;  // contour pixels since the last vertex
      for (const cv::Point& p : contour) {
        if (++since < cell) continue;
        const float z = depth.at<float>(p.y, p.x);
        if (!(z > 0.0f)) continue;
        Vertex v;
        v.x = p.x;
        v.y = p.y;
        v.in_cam = camera.Unproject(Eigen::Vector2d(v.x, v.y), z);
        since = 0;
        ++rep.candidate_vertices;
        if (options.max_radius_m > 0.0 && (obj_from_cam * v.in_cam).norm() > options.max_radius_m) {
          ++rep.dropped_far;
          continue;
        }
        vertices.push_back(v);
      }
    }
  }
  // One vertex per pixel (an outline vertex may fall on a box's).
  std::sort(vertices.begin(), vertices.end(),
            [](const Vertex& a, const Vertex& b) { return a.y != b.y ? a.y < b.y : a.x < b.x; });
  vertices.erase(
      std::unique(vertices.begin(), vertices.end(),
                  [](const Vertex& a, const Vertex& b) { return a.x == b.x && a.y == b.y; }),
      vertices.end());
  if (vertices.size() < 3) {
    return fail(fmt::format("{} vertices with depth on the object (3 needed)", vertices.size()));
  }

  // Step 4: Delaunay triangulation in the image.
  cv::Subdiv2D subdiv(cv::Rect(region.x - 1, region.y - 1, region.width + 2, region.height + 2));
  std::unordered_map<long, int> index_of;
  for (int i = 0; i < static_cast<int>(vertices.size()); ++i) {
    subdiv.insert(
        cv::Point2f(static_cast<float>(vertices[i].x), static_cast<float>(vertices[i].y)));
    index_of[long(vertices[i].y) * size.width + vertices[i].x] = i;
  }
  std::vector<cv::Vec6f> triangle_list;
  subdiv.getTriangleList(triangle_list);
  auto lookup = [&](float x, float y) {
    const int xi = static_cast<int>(std::lround(x)), yi = static_cast<int>(std::lround(y));
    if (xi < 0 || yi < 0 || xi >= size.width || yi >= size.height) return -1;
    const auto it = index_of.find(long(yi) * size.width + xi);
    return it == index_of.end() ? -1 : it->second;
  };
  auto inside_mask = [&](double x, double y) {
    const int xi = static_cast<int>(std::lround(x)), yi = static_cast<int>(std::lround(y));
    return xi >= 0 && yi >= 0 && xi < size.width && yi < size.height && mask.at<uint8_t>(yi, xi);
  };
  std::vector<Eigen::Vector3i> triangles;
  for (const cv::Vec6f& t : triangle_list) {
    int ids[3] = {lookup(t[0], t[1]), lookup(t[2], t[3]), lookup(t[4], t[5])};
    if (ids[0] < 0 || ids[1] < 0 || ids[2] < 0) continue;  // Subdiv2D's outer vertices
    ++rep.triangles_delaunay;
    const Vertex& a = vertices[ids[0]];
    const Vertex& b = vertices[ids[1]];
    const Vertex& c = vertices[ids[2]];
    // Beyond the thesis: outside the silhouette (centroid or an edge's midpoint).
    const double gx = (a.x + b.x + c.x) / 3.0, gy = (a.y + b.y + c.y) / 3.0;
    if (!inside_mask(gx, gy) || !inside_mask(0.5 * (a.x + b.x), 0.5 * (a.y + b.y)) ||
        !inside_mask(0.5 * (b.x + c.x), 0.5 * (b.y + c.y)) ||
        !inside_mask(0.5 * (c.x + a.x), 0.5 * (c.y + a.y))) {
      ++rep.dropped_outside;
      continue;
    }
    // ... or across a depth discontinuity: the depth measured at its centroid or an edge's
    // midpoint is not that of the plane through its vertices there (inverse depth is linear
    // in the image, so the plane's depth at the mean of pixels is the harmonic mean).
    const double ia = 1.0 / a.in_cam.z(), ib = 1.0 / b.in_cam.z(), ic = 1.0 / c.in_cam.z();
    const double step =
        std::max(options.min_depth_step_m, options.max_depth_step * 3.0 / (ia + ib + ic));
    auto off_plane = [&](double x, double y, double inverse_depth) {
      const float measured =
          depth.at<float>(static_cast<int>(std::lround(y)), static_cast<int>(std::lround(x)));
      return measured > 0.0f && std::abs(measured - 1.0 / inverse_depth) > step;
    };
    if (off_plane(gx, gy, (ia + ib + ic) / 3.0) ||
        off_plane(0.5 * (a.x + b.x), 0.5 * (a.y + b.y), 0.5 * (ia + ib)) ||
        off_plane(0.5 * (b.x + c.x), 0.5 * (b.y + c.y), 0.5 * (ib + ic)) ||
        off_plane(0.5 * (c.x + a.x), 0.5 * (c.y + a.y), 0.5 * (ic + ia))) {
      ++rep.dropped_discontinuity;
      continue;
    }
    // Counter-clockwise seen from the camera (outside).
    const Eigen::Vector3d n = (b.in_cam - a.in_cam).cross(c.in_cam - a.in_cam);
    if (n.dot(a.in_cam) > 0.0) std::swap(ids[1], ids[2]);
    triangles.emplace_back(ids[0], ids[1], ids[2]);
  }
  if (triangles.empty()) return fail("no triangle left on the object");

  // The vertices the triangles use, in the object frame.
  Mesh mesh;
  std::vector<int> new_index(vertices.size(), -1);
  for (Eigen::Vector3i& t : triangles) {
    for (int k = 0; k < 3; ++k) {
      int& id = new_index[t[k]];
      if (id < 0) {
        id = mesh.num_vertices();
        mesh.vertices.push_back((obj_from_cam * vertices[t[k]].in_cam).cast<float>());
      }
      t[k] = id;
    }
  }
  mesh.triangles = std::move(triangles);
  mesh.ComputeNormals();
  rep.vertices = mesh.num_vertices();
  rep.triangles = mesh.num_triangles();

  // SPEC 5.3: the reference image is the texture, projected from where it was taken.
  Eigen::Vector3f centre;
  float radius = 0.0f;
  mesh.BoundingSphere(&centre, &radius);
  const PixelRect rect{grown.x, grown.y, grown.x + grown.width, grown.y + grown.height};
  std::optional<Projector> projector =
      CaptureProjector(mesh, camera, cam_from_obj, image, rect, std::max(0.003f, 0.05f * radius));
  if (!projector) return fail("the mesh covers none of the reference image");
  // The mesh is the surface the projector saw, all of it in its view: no self-occlusion to
  // test (the depth test would only drop colours at its rims, where rendered and seen depth
  // part by a pixel).
  projector->depth.release();
  mesh.projectors.push_back(std::move(*projector));
  mesh.Check("on-line model");
  return mesh;
}

}  // namespace unseen
