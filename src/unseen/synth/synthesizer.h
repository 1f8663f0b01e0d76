// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Renders a synthetic scene (synth/scene.h) frame by frame and writes it as a DATASET.md
// sequence: colour images per camera, ground truth, the model in millimetres, visible-
// object masks and optionally 16-bit depth.
//
// Per camera and frame: a background plane (image, colour or generated clutter), the object
// shaded with the scene's lights (Lambertian: ambient + directional + point), occluders,
// all composited by depth at `antialias` x the resolution and area-averaged down (so the
// tracker never sees aliased edges); then sensor blur, gain and noise. Depth and masks are
// taken at the centre sub-sample of each pixel, which is exactly the pixel centre (the
// factor is odd), so they agree with a plain render at the ground-truth pose. A pixel's
// mask is set where the object is the nearest surface (occluded pixels are excluded).
//
// Deterministic: every random draw comes from std::mt19937 seeded from (scene seed, frame,
// camera), so a frame's content does not depend on which other frames were rendered.
#pragma once

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "unseen/mesh/mesh.h"
#include "unseen/synth/scene.h"

namespace unseen {

// One rendered frame of the rig.
struct SynthFrame {
  int frame_id = 0;
  double time_s = 0.0;
  Rigid3d world_from_obj;             // ground truth
  std::vector<cv::Mat> images;        // per camera CV_32FC3 BGR [0, 1] after sensor effects
  std::vector<cv::Mat> depths;        // per camera CV_32FC1 metres (0 = none) with depth noise and
                                      // holes; empty when the scene has no depth output
  std::vector<cv::Mat> clean_depths;  // per camera CV_32FC1 metres, exact (before noise)
  std::vector<cv::Mat> masks;         // per camera CV_8UC1, 255 where the object is visible
};

class Synthesizer {
 public:
  // Builds the meshes and background texture of `scene` (checked first). Throws
  // unseen::Error for an invalid scene or unreadable files.
  explicit Synthesizer(Scene scene);

  const Scene& scene() const { return scene_; }
  int num_frames() const { return num_frames_; }
  // The object in metres as rendered (before Scene::model_scale).
  const Mesh& object_mesh() const { return object_mesh_; }

  // Renders frame `frame_id` (0-based; t = frame_id / fps) for every camera (cameras in
  // parallel with OpenMP). Thread-safe.
  SynthFrame RenderFrame(int frame_id) const;

 private:
  void RenderCamera(int camera, int frame_id, SynthFrame* out) const;

  Scene scene_;
  int num_frames_ = 0;
  Mesh object_mesh_;
  Mesh background_mesh_;
  // Per camera, the static background at the supersampled resolution (colour CV_32FC3,
  // depth CV_32FC1), rendered once.
  std::vector<cv::Mat> background_color_, background_depth_;
  std::vector<Mesh> occluder_meshes_;
  std::vector<std::shared_ptr<const Trajectory>> occluder_trajectories_;
};

struct SynthOptions {
  int max_frames = -1;                          // > 0: render only the first max_frames frames
  std::optional<uint64_t> seed = std::nullopt;  // overrides the scene's seed
  bool force_depth = false;  // write depth even when the scene does not ask for it
  bool progress = true;      // progress line on stderr
  void Check() const;
};

struct SynthSummary {
  int frames = 0;
  int cameras = 0;
  double seconds = 0.0;            // wall-clock time of rendering and writing
  double seconds_per_frame = 0.0;  // per rig frame (all cameras)
};

// Renders `scene` into the sequence folder `out_dir` (created; existing frame files are
// overwritten). Throws unseen::Error for bad options or when files cannot be written.
SynthSummary Synthesize(const Scene& scene, const std::string& out_dir,
                        const SynthOptions& options = {});

}  // namespace unseen
