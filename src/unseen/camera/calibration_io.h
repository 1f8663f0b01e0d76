// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Camera calibration files: OpenCV's (as written by its calibration tools through
// cv::FileStorage, YAML, XML or JSON) and ROS camera_info YAML (camera_calibration_parsers).
// They are read with yaml-cpp (YAML, JSON) and pugixml (XML), not cv::FileStorage.
// Both use OpenCV's pixel convention (integer coordinates at pixel centres) and
// distortion order [k1, k2, p1, p2, k3, ...], the same as PinholeCamera, so values are
// taken as they are.
#pragma once

#include <string>

#include "unseen/camera/camera.h"

namespace unseen {

// Reads either format, told apart by content: XML, a `%YAML:1.0` header or an
// `!!opencv-matrix` tag (OpenCV YAML with or without its header) is OpenCV; any other
// YAML is read as ROS camera_info. Throws unseen::Error naming the file, the field and
// the value for a missing file, malformed YAML/XML, a missing key, a matrix of the wrong
// size, a non-pinhole camera matrix (skew), NaN or non-positive focal length / size.
PinholeCamera LoadCameraCalibration(const std::string& path);

// OpenCV calibration: image_width, image_height (int), camera_matrix (3x3) and optional
// distortion_coefficients (4, 5, 8, 12 or 14 values, any row/column shape). All-zero
// distortion is returned as none (empty). Same errors as LoadCameraCalibration.
PinholeCamera LoadOpenCvCalibration(const std::string& path);

// ROS camera_info YAML: image_width, image_height, camera_matrix {rows: 3, cols: 3, data},
// distortion_model (plumb_bob or rational_polynomial; others are rejected) and
// distortion_coefficients {rows, cols, data}. Also accepts the message field names
// (width, height, K/k, D/d). Same errors as LoadCameraCalibration.
PinholeCamera LoadRosCameraInfo(const std::string& path);

// Writes `camera` in OpenCV's calibration format (format by extension: .yaml/.yml, .xml
// or .json) with image_width, image_height, camera_matrix and distortion_coefficients
// (five zeros when the camera has none). Throws unseen::Error for an invalid camera or an
// unwritable file.
void SaveOpenCvCalibration(const std::string& path, const PinholeCamera& camera);

}  // namespace unseen
