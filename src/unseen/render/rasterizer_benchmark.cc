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

void BM_RenderSphere(benchmark::State& state) {
  const int rings = static_cast<int>(state.range(0));
  const int segments = static_cast<int>(state.range(1));
  const bool roi_only = state.range(2) != 0;
  const bool color = state.range(3) != 0;

  PinholeCamera camera;
  camera.width = 512;
  camera.height = 256;
  camera.fx = camera.fy = 837.3;
  camera.cx = 255.5;
  camera.cy = 127.5;
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

}  // namespace
}  // namespace unseen

BENCHMARK_MAIN();
