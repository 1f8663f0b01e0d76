// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Image loading and conversion. Colour images in memory are 3-channel float in [0, 1]
// in OpenCV's BGR channel order (CV_32FC3) throughout unseen.
#pragma once

#include <string>

#include <opencv2/core.hpp>

namespace unseen {

// Loads an 8- or 16-bit colour or grey image as CV_32FC3 BGR in [0, 1]. Throws
// unseen::Error naming the path when it is missing or unreadable.
cv::Mat LoadColorImage(const std::string& path);

// Converts any 1/3/4-channel 8U/16U/32F image to CV_32FC3 BGR in [0, 1] (floats are
// taken as already in [0, 1]). Throws on an empty image or unsupported type.
cv::Mat ToFloatBgr(const cv::Mat& image, const std::string& what = "image");

// Writes a CV_32FC3 [0, 1] (or 8-bit) image to PNG/JPEG, rounding to 8 bits.
void SaveColorImage(const std::string& path, const cv::Mat& image);

}  // namespace unseen
