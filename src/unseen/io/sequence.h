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

// An image of a frame that could not be read (Sequence::TryReadFrame).
struct FrameReadError {
  int camera = 0;       // rig camera index
  bool depth = false;   // the depth image (else the colour image)
  std::string file;     // the image file, or "<video> frame <index>"
  std::string message;  // what went wrong, naming the file
};

// One synchronized frame of the rig.
struct Frame {
  int frame_id = 0;
  double time_s = 0.0;          // frame_id / fps
  std::vector<cv::Mat> images;  // per rig camera: CV_32FC3 BGR [0, 1], undistorted
  std::vector<cv::Mat> depths;  // per rig camera: CV_32FC1 metres (0 = no measurement),
                                // undistorted; empty when the sequence has no depth
  // TryReadFrame only: the images that could not be read, whose entries in `images` or
  // `depths` are empty. Empty for a complete frame.
  std::vector<FrameReadError> errors;
};

class Sequence {
 public:
  // Opens a sequence folder (with sequence.json) or a plain BOP scene folder. Validates
  // every JSON file up front (frame ids agree across cameras, cam_K present, rotations
  // orthonormal) and throws unseen::Error naming file, field and value otherwise.
  //  * sequence.json: only "cameras" is required; fps defaults to 30, reference_camera to
  //    the first camera; object.model is relative to the sequence folder. Unknown fields
  //    (e.g. "frames", "notes") are ignored.
  //  * A plain BOP scene is one camera named after its folder; models are looked for in
  //    <scene>/models, <scene>/../models and <scene>/../../models (BOP dataset layout).
  //  * Intrinsics must be the same in every frame of scene_camera.json (unseen assumes
  //    fixed intrinsics); so must the extrinsics of a rig. A plain BOP scene whose camera
  //    moves uses its camera frame as the world frame (with a warning).
  //  * Frame ids come from scene_camera.json; each frame's image is rgb/<id>.png|.jpg (and
  //    depth/<id>.png when the camera has a depth folder). A frame whose file is absent
  //    (a dropped frame) is a warning here and a read error of that frame; a camera with
  //    no image at all is an error. The image size is read from the first image present;
  //    ReadFrame checks every image against it.
  //  * The object id is `obj_id` when positive (in a scene of several objects, as BOP's
  //    are, the one to track; its model is then models/obj_<id>.*, sequence.json's
  //    object.model being another object's), else sequence.json's object.obj_id, else the
  //    first obj_id of the ground truth. An `obj_id` that the sequence has ground truth for
  //    in no frame is an error.
  static Sequence Open(const std::string& path, int obj_id = 0);
  // A video file or a folder of images (sorted by name) as a one-camera sequence without
  // ground truth. `camera` gives the intrinsics; its width/height may be 0 (taken from
  // the first frame) but must match the frames when given.
  // Video frames are read sequentially: ReadFrame(i) right after ReadFrame(i - 1) is cheap,
  // any other index seeks (CAP_PROP_POS_FRAMES). num_frames is the container's frame
  // count, or found by reading through once when the container does not tell.
  static Sequence OpenVideo(const std::string& path, const PinholeCamera& camera,
                            double fps = 30.0);
  // Image folders take .png/.jpg/.jpeg/.bmp/.tif/.tiff files sorted by file name.
  // Both give one camera "cam0" whose frame is the world frame, and no ground truth.
  static Sequence OpenImageFolder(const std::string& path, const PinholeCamera& camera,
                                  double fps = 30.0);

  Sequence(Sequence&&) noexcept;
  Sequence& operator=(Sequence&&) noexcept;
  ~Sequence();

  const std::string& path() const;
  // Extrinsics of the first frame's scene_camera.json. Images are undistorted at input
  // (cv::remap with maps from cv::initUndistortRectifyMap, computed once per camera) to
  // the *same* K, so the rig's intrinsics are the calibrated K without distortion
  // coefficients; pixels that map outside the source image are black (depth 0).
  const Rig& rig() const;
  int reference_camera() const;  // index into rig().cameras
  double fps() const;
  int num_frames() const;
  int frame_id(int index) const;
  // Loads frame `index` (0-based position, not id). Throws unseen::Error naming the image
  // file when it is missing, unreadable or of the wrong size.
  Frame ReadFrame(int index) const;
  // The same for a stream that must go on: an image that is missing, unreadable (e.g. a
  // truncated PNG) or of the wrong size leaves that camera's entry of Frame::images (or
  // Frame::depths) empty and is listed in Frame::errors with the message ReadFrame would
  // throw; the other cameras are read as usual. Throws only for an index out of range.
  Frame TryReadFrame(int index) const;
  // Restricts the rig to the named cameras (in that order). Throws for an unknown name.
  // The reference camera stays the same camera when selected, else becomes the first.
  void SelectCameras(const std::vector<std::string>& names);

  // True when any selected camera has depth images; Frame::depths then has one entry per
  // camera, empty for cameras without depth.
  bool has_depth() const;
  bool has_ground_truth() const;
  // world_from_obj at frame `index` from the reference camera's scene_gt.json (or the
  // first camera that has it), or nullopt when that frame has no ground truth.
  std::optional<Rigid3d> GroundTruth(int index) const;
  // The same from camera `camera`'s own scene_gt.json (for checking rig consistency).
  std::optional<Rigid3d> GroundTruthFromCamera(int index, int camera) const;

  int obj_id() const;  // 0 when there is no object (videos, image folders)
  // Absolute path of the object model (sequence.json "object.model", else
  // models/obj_<id>.ply|obj|gltf|glb), or empty when there is none.
  std::string model_path() const;
  // Loads the model in metres (BOP models are millimetres). Throws unseen::Error when the
  // sequence has no model or it cannot be read.
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
// called by the destructor if not called explicitly). Images are written as given (with
// the rig's distortion coefficients, if any, as "dist"); depth in metres becomes 16-bit
// PNG value round(depth_m * 1000 / depth_scale), with 0 for no measurement and for depths
// beyond the 16-bit range (one warning). A camera given depth in some frames gets an
// all-zero depth image in the others. Ground truth is written per camera as model->camera
// in millimetres. Throws unseen::Error for a rig or frame that does not fit (image count,
// size or type, invalid pose, frame id written twice).
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
