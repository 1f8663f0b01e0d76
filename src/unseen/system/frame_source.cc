// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/system/frame_source.h"

#include <fmt/format.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "unseen/util/error.h"
#include "unseen/util/logging.h"

namespace unseen {

SequenceFrameSource::SequenceFrameSource(Sequence sequence, int first_frame)
    : owned_(std::move(sequence)), sequence_(&*owned_), first_(first_frame), next_(first_frame) {
  CheckFirstFrame();
}

SequenceFrameSource::SequenceFrameSource(const Sequence* sequence, int first_frame,
                                         std::optional<Frame> first)
    : sequence_(sequence), first_(first_frame), next_(first_frame), first_read_(std::move(first)) {
  UNSEEN_CHECK(sequence_ != nullptr, "frame source: no sequence");
  CheckFirstFrame();
}

void SequenceFrameSource::CheckFirstFrame() const {
  UNSEEN_CHECK(first_ >= 0 && first_ < sequence_->num_frames(),
               "{}: first frame {} is outside [0, {})", sequence_->path(), first_,
               sequence_->num_frames());
}

std::optional<Frame> SequenceFrameSource::Next() {
  if (next_ >= sequence_->num_frames()) return std::nullopt;
  if (next_++ == first_ && first_read_) return std::exchange(first_read_, std::nullopt);
  return sequence_->TryReadFrame(next_ - 1);
}

std::optional<Rigid3d> SequenceFrameSource::GroundTruth(int n) const {
  const int index = first_ + n;
  if (n < 0 || index >= sequence_->num_frames()) return std::nullopt;
  return sequence_->GroundTruth(index);
}

void CaptureOptions::Check() const {
  UNSEEN_CHECK(max_failed_reads >= 1, "capture: max_failed_reads {} must be >= 1",
               max_failed_reads);
  UNSEEN_CHECK(fps > 0.0, "capture: fps {} must be > 0", fps);
}

CaptureFrameSource::CaptureFrameSource(int device, const PinholeCamera& camera,
                                       const CaptureOptions& options)
    : options_((options.Check(), options)), name_(fmt::format("camera {}", device)) {
  UNSEEN_CHECK(device >= 0, "capture: camera index {} must be >= 0", device);
  capture_.open(device);
  UNSEEN_CHECK(capture_.isOpened(), "capture: cannot open camera {}", device);
  Open(camera);
}

CaptureFrameSource::CaptureFrameSource(const std::string& video_file, const PinholeCamera& camera,
                                       const CaptureOptions& options)
    : options_((options.Check(), options)), name_(video_file) {
  capture_.open(video_file);
  UNSEEN_CHECK(capture_.isOpened(), "capture: cannot open video '{}'", video_file);
  Open(camera);
}

void CaptureFrameSource::Open(const PinholeCamera& camera) {
  const int width = static_cast<int>(capture_.get(cv::CAP_PROP_FRAME_WIDTH));
  const int height = static_cast<int>(capture_.get(cv::CAP_PROP_FRAME_HEIGHT));
  PinholeCamera intrinsics = camera;
  if (intrinsics.width == 0 && intrinsics.height == 0) {
    intrinsics.width = width;
    intrinsics.height = height;
  }
  intrinsics.Check(name_ + ": calibration");
  UNSEEN_CHECK(width <= 0 || (width == intrinsics.width && height == intrinsics.height),
               "{}: frames are {}x{} but the calibration is for {}x{}", name_, width, height,
               intrinsics.width, intrinsics.height);
  if (intrinsics.HasDistortion()) {
    const cv::Mat k = (cv::Mat_<double>(3, 3) << intrinsics.fx, 0.0, intrinsics.cx, 0.0,
                       intrinsics.fy, intrinsics.cy, 0.0, 0.0, 1.0);
    cv::initUndistortRectifyMap(k, intrinsics.distortion, cv::noArray(), k,
                                cv::Size(intrinsics.width, intrinsics.height), CV_32FC1, map_x_,
                                map_y_);
  }
  rig_.cameras.push_back({"cam0", intrinsics, Rigid3d()});
  const double reported = capture_.get(cv::CAP_PROP_FPS);
  fps_ = reported > 0.0 && reported < 1000.0 ? reported : options_.fps;
}

std::optional<Frame> CaptureFrameSource::Next() {
  const PinholeCamera& intrinsics = rig_.cameras[0].intrinsics;
  cv::Mat raw;
  int failed = 0;
  while (!capture_.read(raw) || raw.empty()) {
    if (++failed >= options_.max_failed_reads) {
      UNSEEN_LOG_INFO("{}: no frame after {} reads: the source has stopped", name_, failed);
      return std::nullopt;
    }
  }
  Frame frame;
  frame.frame_id = frames_;
  frame.time_s = frames_ / fps_;
  ++frames_;
  if (raw.cols != intrinsics.width || raw.rows != intrinsics.height || raw.channels() != 3) {
    frame.images = {cv::Mat()};
    frame.errors.push_back(
        {0, false, fmt::format("{} frame {}", name_, frame.frame_id),
         fmt::format("frame is {}x{} with {} channels; the calibration is "
                     "for {}x{} colour",
                     raw.cols, raw.rows, raw.channels(), intrinsics.width, intrinsics.height)});
    return frame;
  }
  if (!map_x_.empty()) {
    cv::Mat undistorted;
    cv::remap(raw, undistorted, map_x_, map_y_, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
              cv::Scalar::all(0));
    raw = undistorted;
  }
  cv::Mat image;
  raw.convertTo(image, CV_32FC3, 1.0 / 255.0);
  frame.images = {image};
  return frame;
}

}  // namespace unseen
