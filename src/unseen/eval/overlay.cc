// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/eval/overlay.h"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "unseen/io/sequence.h"
#include "unseen/util/error.h"
#include "unseen/util/files.h"
#include "unseen/util/logging.h"
#include "unseen/util/progress.h"

namespace unseen {
namespace {

bool ValidColor(const cv::Scalar& c) {
  for (int i = 0; i < 3; ++i) {
    if (!(c[i] >= 0.0 && c[i] <= 255.0)) return false;
  }
  return true;
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

void DrawOutline(const Mesh& mesh, const PinholeCamera& camera, const Rigid3d& cam_from_obj,
                 const cv::Scalar& color, const OverlayOptions& options, RenderBuffers* buffers,
                 cv::Mat* image) {
  if (!cam_from_obj.IsValid()) return;
  const auto outline =
      SilhouetteOutline(mesh, camera, cam_from_obj, options.roi_margin_px, buffers);
  cv::polylines(*image, outline, /*isClosed=*/true, color, options.line_thickness_px,
                options.line_thickness_px > 1 ? cv::LINE_AA : cv::LINE_8);
}

}  // namespace

void OverlayOptions::Check() const {
  UNSEEN_CHECK(roi_margin_px >= 0, "OverlayOptions: roi_margin_px must be >= 0, got {}",
               roi_margin_px);
  UNSEEN_CHECK(line_thickness_px >= 1, "OverlayOptions: line_thickness_px must be >= 1, got {}",
               line_thickness_px);
  UNSEEN_CHECK(std::isfinite(font_scale) && font_scale > 0.0,
               "OverlayOptions: font_scale must be > 0, got {}", font_scale);
  UNSEEN_CHECK(
      ValidColor(tracking_color) && ValidColor(lost_color) && ValidColor(ground_truth_color),
      "OverlayOptions: colours must be BGR values in [0, 255]");
}

std::vector<std::vector<cv::Point>> SilhouetteOutline(const Mesh& mesh, const PinholeCamera& camera,
                                                      const Rigid3d& cam_from_obj, int margin_px,
                                                      RenderBuffers* buffers) {
  UNSEEN_CHECK(margin_px >= 0, "SilhouetteOutline: margin_px must be >= 0, got {}", margin_px);
  Eigen::Vector3f centre;
  float radius = 0.0f;
  mesh.BoundingSphere(&centre, &radius);
  const Eigen::Vector3d centre_in_cam = cam_from_obj * centre.cast<double>();
  const std::optional<PixelRect> rect = camera.SphereRect(centre_in_cam, radius);
  if (!rect) return {};
  const PixelRect roi = rect->Grow(margin_px).Intersect(camera.ImageRect());
  if (roi.empty()) return {};

  RenderOptions render_options;
  render_options.write_color = false;
  render_options.cull_back_faces = false;  // the silhouette of open meshes too
  RenderBuffers local;
  RenderBuffers* out = buffers != nullptr ? buffers : &local;
  Render(mesh, camera, cam_from_obj, roi, render_options, out);
  if (out->mask.empty()) return {};

  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(out->mask.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE,
                   cv::Point(out->roi.x0, out->roi.y0));
  return contours;
}

void DrawOverlay(const Mesh& mesh, const PinholeCamera& camera, const Rigid3d& cam_from_world,
                 const OverlayFrame& frame, const OverlayOptions& options, cv::Mat* image) {
  options.Check();
  UNSEEN_CHECK(image != nullptr && image->type() == CV_8UC3,
               "DrawOverlay: the image must be CV_8UC3");
  UNSEEN_CHECK(image->cols == camera.width && image->rows == camera.height,
               "DrawOverlay: image size {}x{} does not match the camera's {}x{}", image->cols,
               image->rows, camera.width, camera.height);
  RenderBuffers buffers;
  if (options.draw_ground_truth && frame.ground_truth) {
    DrawOutline(mesh, camera, cam_from_world * *frame.ground_truth, options.ground_truth_color,
                options, &buffers, image);
  }
  std::string text = fmt::format("frame {}", frame.frame);
  if (frame.estimate != nullptr) {
    const PoseRecord& r = *frame.estimate;
    const bool tracking = r.status == TrackStatus::kTracking;
    if (tracking || options.draw_lost_pose) {
      DrawOutline(mesh, camera, cam_from_world * r.world_from_obj,
                  tracking ? options.tracking_color : options.lost_color, options, &buffers, image);
    }
    text += fmt::format("  {}  conf {:.2f}", ToString(r.status), r.confidence);
    if (tracking && frame.ground_truth && r.world_from_obj.IsValid()) {
      const PoseDifference d = Difference(*frame.ground_truth, r.world_from_obj);
      text += fmt::format("  err {:.1f} mm {:.1f} deg", d.translation * 1000.0,
                          d.rotation_rad * 180.0 / M_PI);
    }
  } else {
    text += "  no pose";
  }
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  int baseline = 0;
  double scale = options.font_scale;
  cv::Size size = cv::getTextSize(text, font, scale, 1, &baseline);
  if (size.width > image->cols - 12) {  // shrink to fit narrow images
    scale *= double(image->cols - 12) / size.width;
    size = cv::getTextSize(text, font, scale, 1, &baseline);
  }
  const cv::Point origin(6, 6 + size.height);
  cv::rectangle(*image, cv::Point(2, 2), cv::Point(10 + size.width, 10 + size.height + baseline),
                cv::Scalar(0, 0, 0), cv::FILLED);
  cv::putText(*image, text, origin, font, scale, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
}

struct OverlaySink::Video {
  cv::VideoWriter writer;
};

OverlaySink::OverlaySink(const std::string& path, double fps, cv::Size size)
    : path_(path), size_(size) {
  namespace fs = std::filesystem;
  UNSEEN_CHECK(size.width > 0 && size.height > 0, "overlay '{}': invalid frame size {}x{}", path,
               size.width, size.height);
  const std::string ext = Lower(fs::path(path).extension().string());
  if (ext == ".mp4" || ext == ".avi") {
    UNSEEN_CHECK(std::isfinite(fps) && fps > 0.0, "overlay '{}': fps must be > 0, got {}", path,
                 fps);
    is_video_ = true;
    const int fourcc = ext == ".mp4" ? cv::VideoWriter::fourcc('m', 'p', '4', 'v')
                                     : cv::VideoWriter::fourcc('M', 'J', 'P', 'G');
    const fs::path parent = fs::absolute(path).parent_path();
    UNSEEN_CHECK(IsFolder(parent), "overlay '{}': the folder '{}' does not exist", path,
                 parent.string());
    video_ = std::make_unique<Video>();
    // FFmpeg first (it writes both containers); then whatever backend OpenCV has.
    video_->writer.open(path, cv::CAP_FFMPEG, fourcc, fps, size, /*isColor=*/true);
    if (!video_->writer.isOpened()) {
      video_->writer.open(path, fourcc, fps, size, /*isColor=*/true);
    }
    UNSEEN_CHECK(video_->writer.isOpened(),
                 "overlay '{}': cannot open a video writer ({} codec, {}x{} at {} fps); check "
                 "that the folder exists and OpenCV has a video backend, or give a folder for "
                 "PNG frames",
                 path, ext == ".mp4" ? "mp4v" : "MJPG", size.width, size.height, fps);
  } else {
    UNSEEN_CHECK(ext.empty() || IsFolder(path),
                 "overlay '{}': unknown extension '{}', expected .mp4, .avi or a folder", path,
                 ext);
    std::error_code ec;
    fs::create_directories(path, ec);
    UNSEEN_CHECK(IsFolder(path), "overlay '{}': cannot create the folder ({})", path,
                 ec.message());
  }
}

OverlaySink::~OverlaySink() {
  if (video_) video_->writer.release();
}

void OverlaySink::Write(const cv::Mat& image_bgr8, int frame_id) {
  UNSEEN_CHECK(image_bgr8.type() == CV_8UC3 && image_bgr8.size() == size_,
               "overlay '{}': frame {} is {}x{} (type {}), expected {}x{} CV_8UC3", path_, frame_id,
               image_bgr8.cols, image_bgr8.rows, image_bgr8.type(), size_.width, size_.height);
  if (is_video_) {
    video_->writer.write(image_bgr8);
    return;
  }
  const std::string file =
      (std::filesystem::path(path_) / fmt::format("frame_{:06d}.png", frame_id)).string();
  bool ok = false;
  try {
    ok = cv::imwrite(file, image_bgr8);
  } catch (const cv::Exception& e) {
    ThrowError("overlay: cannot write '{}': {}", file, e.what());
  }
  UNSEEN_CHECK(ok, "overlay: cannot write '{}'", file);
}

int WriteOverlay(const Sequence& sequence, const std::vector<PoseRecord>& poses, int camera_index,
                 const std::string& out_path, double fps, const OverlayOptions& options) {
  options.Check();
  const Rig& rig = sequence.rig();
  UNSEEN_CHECK(camera_index >= 0 && camera_index < rig.size(),
               "overlay: camera index {} out of range (the sequence '{}' has {} cameras)",
               camera_index, sequence.path(), rig.size());
  UNSEEN_CHECK(!sequence.model_path().empty(), "overlay: sequence '{}' has no object model",
               sequence.path());
  const Mesh mesh = sequence.LoadModel();
  const RigCamera& camera = rig.cameras[camera_index];
  const Rigid3d cam_from_world = camera.cam_from_world();

  std::map<int, const PoseRecord*> by_frame;
  for (const PoseRecord& r : poses) {
    UNSEEN_CHECK(by_frame.emplace(r.frame, &r).second,
                 "overlay: the pose stream has frame {} more than once", r.frame);
  }

  OverlaySink sink(out_path, fps > 0.0 ? fps : sequence.fps(),
                   cv::Size(camera.intrinsics.width, camera.intrinsics.height));
  ProgressLine progress("overlay", sequence.num_frames(), options.show_progress);
  const bool has_gt = sequence.has_ground_truth();
  for (int i = 0; i < sequence.num_frames(); ++i) {
    const Frame frame = sequence.TryReadFrame(i);
    cv::Mat image;
    if (frame.images.at(camera_index).empty()) {  // a dropped or damaged frame: black
      for (const FrameReadError& e : frame.errors) {
        if (e.camera == camera_index && !e.depth) UNSEEN_LOG_WARN("overlay: {}", e.message);
      }
      image = cv::Mat::zeros(camera.intrinsics.height, camera.intrinsics.width, CV_8UC3);
    } else {
      frame.images[camera_index].convertTo(image, CV_8UC3, 255.0);
    }
    OverlayFrame what;
    what.frame = frame.frame_id;
    auto it = by_frame.find(frame.frame_id);
    if (it != by_frame.end()) what.estimate = it->second;
    if (has_gt) what.ground_truth = sequence.GroundTruth(i);
    DrawOverlay(mesh, camera.intrinsics, cam_from_world, what, options, &image);
    sink.Write(image, frame.frame_id);
    progress.Update(i + 1);
  }
  progress.Finish();
  return sequence.num_frames();
}

}  // namespace unseen
