// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/image/image_io.h"

#include <filesystem>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "unseen/util/error.h"
#include "unseen/util/files.h"

namespace unseen {

cv::Mat ToFloatBgr(const cv::Mat& image, const std::string& what) {
  UNSEEN_CHECK(!image.empty(), "{}: image is empty", what);
  cv::Mat bgr;
  switch (image.channels()) {
    case 1: cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR); break;
    case 3: bgr = image; break;
    case 4: cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR); break;
    default: ThrowError("{}: unsupported channel count {}", what, image.channels());
  }
  cv::Mat out;
  switch (bgr.depth()) {
    case CV_8U: bgr.convertTo(out, CV_32F, 1.0 / 255.0); break;
    case CV_16U: bgr.convertTo(out, CV_32F, 1.0 / 65535.0); break;
    case CV_32F: out = bgr.clone(); break;
    case CV_64F: bgr.convertTo(out, CV_32F); break;
    default: ThrowError("{}: unsupported pixel depth (OpenCV depth code {})", what, bgr.depth());
  }
  return out;
}

cv::Mat LoadColorImage(const std::string& path) {
  UNSEEN_CHECK(IsFile(path), "{}: image file not found", path);
  const cv::Mat raw = cv::imread(path, cv::IMREAD_ANYCOLOR | cv::IMREAD_ANYDEPTH);
  UNSEEN_CHECK(!raw.empty(), "{}: not a readable image", path);
  return ToFloatBgr(raw, path);
}

void SaveColorImage(const std::string& path, const cv::Mat& image) {
  UNSEEN_CHECK(!image.empty(), "{}: refusing to write an empty image", path);
  cv::Mat out;
  if (image.depth() == CV_32F || image.depth() == CV_64F) {
    image.convertTo(out, CV_8U, 255.0);
  } else {
    out = image;
  }
  UNSEEN_CHECK(cv::imwrite(path, out), "{}: could not write image", path);
}

}  // namespace unseen
