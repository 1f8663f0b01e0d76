// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Overlay videos: the model's silhouette outline drawn at the estimated pose over the
// frames of a sequence (and at the ground-truth pose in another colour when present), so a
// person can see how well a track follows the object.
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/io/pose_stream.h"
#include "unseen/mesh/mesh.h"
#include "unseen/render/rasterizer.h"

namespace unseen {

class Sequence;

struct OverlayOptions {
  int roi_margin_px = 4;                    // growth of the bounding-sphere rectangle, px (>= 0)
  int line_thickness_px = 2;                // outline thickness, px (>= 1)
  cv::Scalar tracking_color = {0, 255, 0};  // BGR 8-bit: estimate while tracking
  cv::Scalar lost_color = {0, 0, 255};      // BGR 8-bit: estimate when lost/searching
  cv::Scalar ground_truth_color = {255, 128, 0};  // BGR 8-bit: ground truth
  bool draw_ground_truth = true;  // outline of the ground truth when the frame has one
  bool draw_lost_pose = true;     // outline of the reported pose of lost/searching frames
  double font_scale = 0.6;        // of the status line (> 0)
  bool show_progress = false;     // WriteOverlay: a progress line on stderr
  void Check() const;
};

// Outer silhouette outline of `mesh` seen from `camera` with the object at `cam_from_obj`,
// as closed polygons in image pixels (the boundary pixels of the coverage mask, from
// cv::findContours). Renders depth/mask only in the model's bounding-sphere rectangle
// grown by `margin_px`. Empty when the object is not in view. `buffers` (optional) is
// reused for the render and holds its mask afterwards.
std::vector<std::vector<cv::Point>> SilhouetteOutline(const Mesh& mesh, const PinholeCamera& camera,
                                                      const Rigid3d& cam_from_obj,
                                                      int margin_px = 4,
                                                      RenderBuffers* buffers = nullptr);

// What to draw over one frame.
struct OverlayFrame {
  int frame = 0;                         // frame id, printed
  const PoseRecord* estimate = nullptr;  // the stream's record of this frame, or null
  std::optional<Rigid3d> ground_truth;   // world_from_obj, when known
};

// Draws the outlines and a status line ("frame N  tracking  conf 0.93  err 3.1 mm 0.8 deg")
// over `image` (CV_8UC3 BGR, the size of `camera`), for the camera at `cam_from_world`.
void DrawOverlay(const Mesh& mesh, const PinholeCamera& camera, const Rigid3d& cam_from_world,
                 const OverlayFrame& frame, const OverlayOptions& options, cv::Mat* image);

// Sink of overlay frames: a video file (.mp4 with the mp4v codec, .avi with MJPG) or a
// folder of PNG images (frame_000000.png, ...; any path without one of these extensions,
// created when absent). Throws unseen::Error when the file cannot be opened or the frame
// size changes.
class OverlaySink {
 public:
  OverlaySink(const std::string& path, double fps, cv::Size size);
  ~OverlaySink();
  void Write(const cv::Mat& image_bgr8, int frame_id);
  bool is_video() const { return is_video_; }

 private:
  std::string path_;
  cv::Size size_;
  bool is_video_ = false;
  struct Video;
  std::unique_ptr<Video> video_;
};

// Writes the overlay of every frame of `sequence` (camera `camera_index` of its rig) with
// the poses of `poses` (matched by frame id) to `out_path` (see OverlaySink); fps <= 0 uses
// the sequence's. A frame whose image cannot be read is drawn over black, with a warning. Returns the number of frames written. Throws unseen::Error when the
// sequence has no model, the camera index is out of range, or the output cannot be written.
int WriteOverlay(const Sequence& sequence, const std::vector<PoseRecord>& poses, int camera_index,
                 const std::string& out_path, double fps = 0.0, const OverlayOptions& options = {});

}  // namespace unseen
