// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// ParseScene (synth/scene.h): the input is the YAML text of a scene. Relative file paths
// resolve against a folder holding a pose stream (poses.csv), an image (t.png) and a mesh
// (m.obj). A scene it returns passes Scene::Check, and its trajectories give valid poses
// over the frames it renders.
#include <opencv2/imgcodecs.hpp>

#include "fuzz/fuzz_support.h"
#include "unseen/synth/scene.h"

namespace {

const unseen::fuzz::Scratch& Folder() {
  static const unseen::fuzz::Scratch scratch("scene");
  static const bool written = [] {
    scratch.Write("poses.csv",
                  "frame,time_s,status,confidence,tx,ty,tz,qx,qy,qz,qw\n"
                  "0,0,tracking,1,0,0,1,0,0,0,1\n"
                  "1,0.1,tracking,1,0.01,0,1,0,0.0499792,0,0.99875\n");
    cv::imwrite((scratch.dir() / "t.png").string(),
                cv::Mat(4, 8, CV_8UC3, cv::Scalar(40, 90, 200)));
    scratch.Write("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    return true;
  }();
  (void)written;
  return scratch;
}

void CheckTrajectory(const unseen::Trajectory& trajectory, double fps, int frames,
                     const std::string& what) {
  for (int frame : {0, frames / 2, frames - 1}) {
    const unseen::Rigid3d pose = trajectory.WorldFromObj(frame / fps);
    UNSEEN_FUZZ_EXPECT(pose.IsValid(), "{} at frame {} of {} ({} fps): {}", what, frame, frames,
                       fps, pose.ToString());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace unseen;
  fuzz::Init();
  const std::string base_dir = Folder().dir().string();
  const std::string text(fuzz::AsText(data, size));
  const std::string path = "scene.yaml";
  fuzz::ExpectReaderContract("ParseScene", path, [&] {
    const Scene scene = ParseScene(text, path, base_dir);
    try {
      scene.Check();
    } catch (const Error& e) {
      fuzz::Fail(std::string("ParseScene returned a scene that fails its check: ") + e.what());
    }
    int frames = 0;
    try {
      frames = scene.NumFrames();
    } catch (const Error& e) {  // a trajectory too long to render; ParseScene need not know
      UNSEEN_FUZZ_EXPECT(std::string(e.what()).find(path) != std::string::npos,
                         "NumFrames error without the file: {}", e.what());
      frames = 1;
    }
    CheckTrajectory(*scene.trajectory, scene.fps, frames, "trajectory");
    for (const OccluderSpec& occluder : scene.occluders) {
      if (occluder.trajectory) {
        CheckTrajectory(*occluder.trajectory, scene.fps, frames, "occluder trajectory");
      }
    }
  });
  return 0;
}
