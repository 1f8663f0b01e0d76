// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Per-frame cost of the tracker on the thesis camera (512x256, 34 deg HFOV) with the
// 96 mm lettered cube at 1 m, one thread: steady tracking of a still object, and the
// alignment of a frame that starts 5 mm / 2 deg off.
#include <benchmark/benchmark.h>
#include <opencv2/imgproc.hpp>

#include "unseen/mesh/primitives.h"
#include "unseen/render/rasterizer.h"
#include "unseen/track/tracker.h"

namespace unseen {
namespace {

struct Scene {
  Rig rig;
  Mesh cube = MakeLetteredCube(0.096, 256);
  Rigid3d truth{ExpSO3(Eigen::Vector3d(0.45, 0.7, 0.1)), Eigen::Vector3d(0.02, -0.01, 1.0)};
  cv::Mat image;
  Scene() {
    PinholeCamera cam;
    cam.width = 512;
    cam.height = 256;
    cam.fx = cam.fy = 837.3;
    cam.cx = 255.5;
    cam.cy = 127.5;
    rig.cameras.push_back({"cam0", cam, Rigid3d()});
    const PinholeCamera fine = cam.Scaled(0.5);
    RenderBuffers b;
    Render(cube, fine, truth, fine.ImageRect(), RenderOptions(), &b);
    cv::Mat big(fine.height, fine.width, CV_32FC3, cv::Scalar(0.9, 0.85, 0.8));
    b.color.copyTo(big, b.mask);
    cv::resize(big, image, cv::Size(cam.width, cam.height), 0, 0, cv::INTER_AREA);
  }
};

void BM_TrackStillObject(benchmark::State& state) {
  Scene scene;
  TrackerOptions options;
  options.predictor.type = PredictorType::kHold;
  Tracker tracker(scene.rig, scene.cube, options);
  tracker.Initialize(scene.truth);
  double rounds = 0;
  for (auto _ : state) {
    const TrackResult r = tracker.Track({scene.image});
    for (int n : r.summary.iterations_per_level) rounds += n;
  }
  state.counters["rounds"] = benchmark::Counter(rounds, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_TrackStillObject)->Unit(benchmark::kMillisecond);

void BM_AlignFromOffset(benchmark::State& state) {
  Scene scene;
  Tracker tracker(scene.rig, scene.cube);
  const Rigid3d start(ExpSO3(Eigen::Vector3d(0.02, -0.02, 0.01)) * scene.truth.rotation(),
                      scene.truth.translation() + Eigen::Vector3d(0.005, -0.003, 0.01));
  double rounds = 0;
  for (auto _ : state) {
    const TrackResult r = tracker.Align({scene.image}, start);
    for (int n : r.summary.iterations_per_level) rounds += n;
  }
  state.counters["rounds"] = benchmark::Counter(rounds, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_AlignFromOffset)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace unseen

BENCHMARK_MAIN();
