// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Where frames come from (SPEC 6): one interface for a sequence folder (any number of
// cameras, depth), a video file or image folder with its calibration, and a live camera.
// A live camera and a video file go through the same class (OpenCV's VideoCapture), so a
// test with a video file exercises the camera's path.
#pragma once

#include <memory>
#include <opencv2/videoio.hpp>
#include <optional>
#include <string>

#include "unseen/camera/camera.h"
#include "unseen/io/sequence.h"

namespace unseen {

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual const Rig& rig() const = 0;
  // The camera the object is selected and modelled in.
  virtual int reference_camera() const { return 0; }
  // Frames per second of the source (0 when unknown).
  virtual double fps() const = 0;
  // The next frame, or std::nullopt at the end (or when a camera stops delivering). An
  // image that cannot be read leaves that camera's entry empty (Frame::errors says why).
  virtual std::optional<Frame> Next() = 0;
  // A sequence behind the source (for ground truth and the model file), or null.
  virtual const Sequence* sequence() const { return nullptr; }
  // The true world_from_obj of the n-th frame Next() returned (0-based), or std::nullopt
  // when the source has none for it.
  virtual std::optional<Rigid3d> GroundTruth(int n) const { return std::nullopt; }
  virtual std::string name() const = 0;
};

// A sequence folder, video file or image folder (io/sequence.h), frame by frame from
// `first_frame`; frames that cannot be read in full come with Frame::errors.
class SequenceFrameSource : public FrameSource {
 public:
  explicit SequenceFrameSource(Sequence sequence, int first_frame = 0);
  // Reads `*sequence`, which must outlive the source. `first`: frame `first_frame` when it
  // was read already (the first Next() returns it instead of reading it again).
  explicit SequenceFrameSource(const Sequence* sequence, int first_frame = 0,
                               std::optional<Frame> first = std::nullopt);
  SequenceFrameSource(const SequenceFrameSource&) = delete;
  SequenceFrameSource& operator=(const SequenceFrameSource&) = delete;
  const Rig& rig() const override { return sequence_->rig(); }
  int reference_camera() const override { return sequence_->reference_camera(); }
  double fps() const override { return sequence_->fps(); }
  std::optional<Frame> Next() override;
  const Sequence* sequence() const override { return sequence_; }
  std::optional<Rigid3d> GroundTruth(int n) const override;
  std::string name() const override { return sequence_->path(); }

 private:
  void CheckFirstFrame() const;

  std::optional<Sequence> owned_;
  const Sequence* sequence_ = nullptr;
  int first_ = 0;
  int next_ = 0;
  std::optional<Frame> first_read_;
};

struct CaptureOptions {
  // Reads that fail in a row before the source counts as stopped (a live camera may drop
  // a frame now and then; a file at its end fails every time).
  int max_failed_reads = 10;
  double fps = 30.0;  // when the capture does not say
  void Check() const;
};

// OpenCV's VideoCapture: a live camera (device index) or a video file, one camera with
// intrinsics `camera` (its image size must match the capture's; distortion is removed).
class CaptureFrameSource : public FrameSource {
 public:
  // Throws unseen::Error naming the device or file when it cannot be opened, or when its
  // frames are not of the calibration's size.
  CaptureFrameSource(int device, const PinholeCamera& camera, const CaptureOptions& options = {});
  CaptureFrameSource(const std::string& video_file, const PinholeCamera& camera,
                     const CaptureOptions& options = {});
  const Rig& rig() const override { return rig_; }
  double fps() const override { return fps_; }
  std::optional<Frame> Next() override;
  std::string name() const override { return name_; }

 private:
  void Open(const PinholeCamera& camera);

  cv::VideoCapture capture_;
  CaptureOptions options_;
  std::string name_;
  Rig rig_;
  double fps_ = 0.0;
  int frames_ = 0;
  cv::Mat map_x_, map_y_;  // undistortion maps, empty without distortion
};

}  // namespace unseen
