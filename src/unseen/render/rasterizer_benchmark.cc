// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Rasterizer speed on the thesis set-up: a textured sphere about 200 px across at 1 m in
// the 512x256 camera (fx = fy = 837.3), rendered into the whole frame or only into the
// 200x200 region around it, with colour or depth and mask only. Arguments:
// rings, segments (2 * segments * (rings - 1) triangles), region (0 frame, 1 sphere
// rectangle), colour (0/1).
#include <benchmark/benchmark.h>

#include "unseen/mesh/primitives.h"
#include "unseen/render/rasterizer.h"

namespace unseen {
namespace {

constexpr double kTurn = 10.0 * M_PI / 180.0;  // the render's view from the projector's

// A camera of focal length `f` pixels whose principal point is the image's centre.
PinholeCamera CentredCamera(int width, int height, double f) {
  PinholeCamera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = camera.fy = f;
  camera.cx = (width - 1) / 2.0;
  camera.cy = (height - 1) / 2.0;
  return camera;
}

void BM_RenderSphere(benchmark::State& state) {
  const int rings = static_cast<int>(state.range(0));
  const int segments = static_cast<int>(state.range(1));
  const bool roi_only = state.range(2) != 0;
  const bool color = state.range(3) != 0;

  const PinholeCamera camera = CentredCamera(512, 256, 837.3);
  // 0.1194 m at 1 m subtends 200 px.
  const double radius = 0.1194;
  const Mesh sphere = MakeTexturedSphere(radius, rings, segments);
  const Eigen::Vector3d centre(0.0, 0.0, 1.0);
  const PixelRect roi = roi_only ? *camera.SphereRect(centre, radius) : camera.ImageRect();

  RenderOptions options;
  options.write_color = color;
  RenderBuffers out;
  int frame = 0;
  for (auto _ : state) {
    // A slowly spinning sphere, as in tracking.
    const Rigid3d cam_from_obj(ExpSO3(Eigen::Vector3d(1.2, 0.01 * (frame++ % 100), 0.3)), centre);
    Render(sphere, camera, cam_from_obj, roi, options, &out);
    benchmark::DoNotOptimize(out.depth.data);
  }
  state.counters["triangles"] = sphere.num_triangles();
  state.counters["roi_px"] = static_cast<double>(roi.area());
  state.counters["covered_px"] = cv::countNonZero(out.mask);
}

// rings x segments: 25 x 50 = 2 400 triangles; 160 x 320 = 101 760 triangles.
BENCHMARK(BM_RenderSphere)
    ->ArgNames({"rings", "segments", "roi", "color"})
    ->ArgsProduct({{25}, {50}, {0, 1}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RenderSphere)
    ->ArgNames({"rings", "segments", "roi", "color"})
    ->ArgsProduct({{160}, {320}, {0, 1}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);

// The same sphere textured by a projector (a live camera frame, as the tracker's live
// appearance and the on-line model have it) seen from 10 degrees off the render's view,
// with the projector's own depth (self-occlusion test); arguments: rings (segments = 2x),
// quads (RenderOptions::shade_quads).
void BM_RenderProjective(benchmark::State& state) {
  const int rings = static_cast<int>(state.range(0));
  const PinholeCamera camera = CentredCamera(640, 480, 600.0);
  const double radius = 0.1;
  Mesh sphere = MakeTexturedSphere(radius, rings, 2 * rings);
  const Eigen::Vector3d centre(0.0, 0.0, 0.5);
  const Rigid3d projector_from_obj(ExpSO3(Eigen::Vector3d(0.9, 0.2, 0.3)), centre);
  RenderOptions options;
  RenderBuffers seen;
  Render(sphere, camera, projector_from_obj, camera.ImageRect(), options, &seen);
  const cv::Rect window(seen.roi.x0, seen.roi.y0, seen.roi.width(), seen.roi.height());
  Projector projector;
  projector.image = cv::Mat(camera.height, camera.width, CV_32FC3, cv::Scalar(0.2, 0.4, 0.6));
  seen.color.copyTo(projector.image(window), seen.mask);
  projector.camera = camera;
  projector.cam_from_obj = projector_from_obj;
  projector.depth = cv::Mat::zeros(camera.height, camera.width, CV_32FC1);
  seen.depth.copyTo(projector.depth(window));
  sphere.projectors.push_back(projector);
  // Rendered 2x2 supersampled, as the tracker does.
  const PinholeCamera fine = camera.Scaled(0.5);
  const PixelRect roi = *fine.SphereRect(centre, radius);
  options.shade_quads = state.range(1) != 0;
  RenderBuffers out;
  int frame = 0;
  for (auto _ : state) {
    const Rigid3d cam_from_obj(
        ExpSO3(Eigen::Vector3d(0.9, 0.2 + 0.1 * kTurn * (frame++ % 2), 0.3 + kTurn)), centre);
    Render(sphere, fine, cam_from_obj, roi, options, &out);
    benchmark::DoNotOptimize(out.color.data);
  }
  state.counters["triangles"] = sphere.num_triangles();
  state.counters["covered_px"] = cv::countNonZero(out.mask);
}

BENCHMARK(BM_RenderProjective)
    ->ArgNames({"rings", "quads"})
    ->ArgsProduct({{25, 80}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace unseen

BENCHMARK_MAIN();
