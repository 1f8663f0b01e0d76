// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Sequences as DATASET.md specifies: a folder with sequence.json and one BOP scene per
// camera, or a plain BOP scene folder (one camera), or a video file / image folder with
// given intrinsics (no ground truth). Frames are read lazily, one at a time.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/mesh/mesh.h"

namespace unseen {

// One synchronized frame of the rig.
struct Frame {
  int frame_id = 0;
  double time_s = 0.0;          // frame_id / fps
  std::vector<cv::Mat> images;  // per rig camera: CV_32FC3 BGR [0, 1], undistorted
  std::vector<cv::Mat> depths;  // per rig camera: CV_32FC1 metres (0 = no measurement),
                                // undistorted; empty when the sequence has no depth
};

class Sequence {
 public:
  // Opens a sequence folder (with sequence.json) or a plain BOP scene folder. Validates
  // every JSON file up front (frame ids agree across cameras, cam_K present, rotations
  // orthonormal) and throws unseen::Error naming file, field and value otherwise.
  static Sequence Open(const std::string& path);
  // A video file or a folder of images (sorted by name) as a one-camera sequence without
  // ground truth. `camera` gives the intrinsics; its width/height may be 0 (taken from
  // the first frame) but must match the frames when given.
  static Sequence OpenVideo(const std::string& path, const PinholeCamera& camera,
                            double fps = 30.0);
  static Sequence OpenImageFolder(const std::string& path, const PinholeCamera& camera,
                                  double fps = 30.0);

  Sequence(Sequence&&) noexcept;
  Sequence& operator=(Sequence&&) noexcept;
  ~Sequence();

  const std::string& path() const;
  const Rig& rig() const;  // extrinsics of the first frame's scene_camera.json
  int reference_camera() const;  // index into rig().cameras
  double fps() const;
  int num_frames() const;
  int frame_id(int index) const;
  // Loads frame `index` (0-based position, not id). Throws unseen::Error naming the image
  // file when it is missing, unreadable or of the wrong size.
  Frame ReadFrame(int index) const;
  // Restricts the rig to the named cameras (in that order). Throws for an unknown name.
  void SelectCameras(const std::vector<std::string>& names);

  bool has_depth() const;
  bool has_ground_truth() const;
  // world_from_obj at frame `index` from the reference camera's scene_gt.json (or the
  // first camera that has it), or nullopt when that frame has no ground truth.
  std::optional<Rigid3d> GroundTruth(int index) const;
  // The same from camera `camera`'s own scene_gt.json (for checking rig consistency).
  std::optional<Rigid3d> GroundTruthFromCamera(int index, int camera) const;

  int obj_id() const;
  // Absolute path of the object model (sequence.json "object.model", else
  // models/obj_<id>.ply|obj|gltf|glb), or empty when there is none.
  std::string model_path() const;
  // Loads the model in metres (BOP models are millimetres).
  Mesh LoadModel() const;

 private:
  struct Impl;
  explicit Sequence(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

struct SequenceWriterOptions {
  double fps = 30.0;
  int obj_id = 1;
  std::string image_extension = ".png";  // ".png" or ".jpg"
  int jpeg_quality = 95;
  double depth_scale = 0.1;  // depth PNG value x depth_scale = millimetres
  std::string notes;
  int reference_camera = 0;
  void Check() const;
};

// Writes a DATASET.md sequence frame by frame; JSON files are written by Finish() (also
// called by the destructor if not called explicitly).
class SequenceWriter {
 public:
  SequenceWriter(const std::string& dir, const Rig& rig, const SequenceWriterOptions& options);
  ~SequenceWriter();
  // Saves the model in millimetres as models/obj_<id>.ply (+ textures) and models_info.json.
  void WriteModel(const Mesh& mesh_in_metres);
  // `images` per camera (CV_32FC3 [0,1] or CV_8UC3); `depths_m` per camera CV_32FC1 metres
  // or empty; `world_from_obj` written as per-camera ground truth when given; `masks`
  // (CV_8UC1 visible-object masks) to camK/mask_visib/<frame>_000000.png when non-empty.
  void WriteFrame(int frame_id, const std::vector<cv::Mat>& images,
                  const std::vector<cv::Mat>& depths_m,
                  const std::optional<Rigid3d>& world_from_obj,
                  const std::vector<cv::Mat>& masks = {});
  void Finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace unseen
