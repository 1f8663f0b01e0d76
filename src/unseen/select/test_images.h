// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Synthetic images for the selection module's tests: cluttered blob scenes, an object
// pasted into them by a similarity, the frame a filter takes.
#pragma once

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "unseen/select/interest_filter.h"

namespace unseen::testing {

// Random filled circles and rectangles of the palette's colours (BGR [0, 1]) on its first
// colour, with a little noise.
inline cv::Mat Blobs(cv::Size size, const std::vector<cv::Scalar>& palette, int blobs, int min_r,
                     int max_r, uint64 seed) {
  cv::RNG rng(seed);
  cv::Mat image(size, CV_32FC3, palette[0]);
  for (int i = 0; i < blobs; ++i) {
    const cv::Point c(rng.uniform(0, size.width), rng.uniform(0, size.height));
    const int r = rng.uniform(min_r, max_r + 1);
    const cv::Scalar colour = palette[rng.uniform(0, static_cast<int>(palette.size()))];
    if (i % 2) {
      cv::circle(image, c, r, colour, cv::FILLED);
    } else {
      cv::rectangle(image, cv::Rect(c.x - r, c.y - r / 2, 2 * r, r), colour, cv::FILLED);
    }
  }
  cv::Mat noise(size, CV_32FC3);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 0.02);
  return image + noise;
}

// Rotation by `angle_deg`, scaling and translation as a homography.
inline cv::Matx33d Similarity(double angle_deg, double scale, double tx, double ty) {
  const double a = angle_deg * CV_PI / 180.0;
  const double c = scale * std::cos(a), s = scale * std::sin(a);
  return {c, -s, tx, s, c, ty, 0.0, 0.0, 1.0};
}

// Pastes `patch` into `scene` mapped by `scene_from_patch`; returns where (CV_8UC1).
inline cv::Mat Paste(const cv::Mat& patch, const cv::Matx33d& scene_from_patch, cv::Mat* scene) {
  cv::Mat warped, mask;
  cv::warpPerspective(patch, warped, scene_from_patch, scene->size());
  cv::warpPerspective(cv::Mat(patch.size(), CV_8UC1, cv::Scalar(255)), mask, scene_from_patch,
                      scene->size(), cv::INTER_NEAREST);
  warped.copyTo(*scene, mask);
  return mask;
}

// The frame a filter sees: `image` from a centred camera of focal length 500 px.
inline FilterFrame FilterFrameOf(const cv::Mat& image) {
  FilterFrame f;
  f.image = image;
  f.camera = PinholeCamera::Centered(image.cols, image.rows, 500.0);
  return f;
}

// Frame `frame` of camera 0 of the development sequence cube_clutter_sidelight
// (../shared/data/sequences): its colour image (CV_8UC3) and the cube's visible mask
// (CV_8UC1). False when the sequence is absent or the frame cannot be read.
inline bool ReadCubeClutterFrame(int frame, cv::Mat* bgr8, cv::Mat* mask) {
  const std::filesystem::path dir = std::filesystem::path(UNSEEN_SOURCE_DIR) /
                                    "../shared/data/sequences/cube_clutter_sidelight/cam0";
  *bgr8 = cv::imread((dir / "rgb" / fmt::format("{:06d}.jpg", frame)).string(), cv::IMREAD_COLOR);
  *mask = cv::imread((dir / "mask_visib" / fmt::format("{:06d}_000000.png", frame)).string(),
                     cv::IMREAD_GRAYSCALE);
  return !bgr8->empty() && !mask->empty();
}

// A folder of its own under the system's temporary one, removed at the end.
class TempFolder {
 public:
  explicit TempFolder(const std::string& name)
      : path_(std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path_);
  }
  ~TempFolder() { std::filesystem::remove_all(path_); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace unseen::testing
