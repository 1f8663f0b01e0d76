// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/camera/calibration_io.h"

#include <filesystem>
#include <fstream>
#include <limits>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "unseen/util/error.h"
#include "unseen/util/testing.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

fs::path TestDir() { return testing::TestDir("calibration"); }

std::string WriteText(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path.string();
}

// `text` with the first `from` replaced by `to` (which must be there).
std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

using testing::ExpectError;

void ExpectCamera(const PinholeCamera& c, int w, int h, double fx, double fy, double cx, double cy,
                  const std::vector<double>& dist) {
  EXPECT_EQ(c.width, w);
  EXPECT_EQ(c.height, h);
  EXPECT_DOUBLE_EQ(c.fx, fx);
  EXPECT_DOUBLE_EQ(c.fy, fy);
  EXPECT_DOUBLE_EQ(c.cx, cx);
  EXPECT_DOUBLE_EQ(c.cy, cy);
  ASSERT_EQ(c.distortion.size(), dist.size());
  for (size_t i = 0; i < dist.size(); ++i) EXPECT_DOUBLE_EQ(c.distortion[i], dist[i]);
}

// As written by OpenCV's calibration sample (samples/cpp/calibration.cpp).
const char kOpenCvYaml[] = R"(%YAML:1.0
---
calibration_time: "Sat 21 Nov 2026 06:40:00 UTC"
image_width: 640
image_height: 480
flags: 0
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 5.2536e+02, 0., 3.1925e+02, 0., 5.2610e+02, 2.4112e+02, 0.,
       0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 5
   cols: 1
   dt: d
   data: [ 1.5e-01, -3.1e-01, 1.2e-03, -4.0e-04, 1.1e-01 ]
avg_reprojection_error: 2.1e-01
)";

const char kRosYaml[] = R"(image_width: 1280
image_height: 720
camera_name: narrow_stereo
camera_matrix:
  rows: 3
  cols: 3
  data: [911.5, 0, 640.2, 0, 912.25, 361.75, 0, 0, 1]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [0.1, -0.2, 0.001, 0.002, 0]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]
projection_matrix:
  rows: 3
  cols: 4
  data: [911.5, 0, 640.2, 0, 0, 912.25, 361.75, 0, 0, 0, 1, 0]
)";

TEST(CalibrationIo, ReadsOpenCvYaml) {
  const std::string path = WriteText(TestDir() / "calib.yaml", kOpenCvYaml);
  const std::vector<double> dist = {0.15, -0.31, 0.0012, -0.0004, 0.11};
  ExpectCamera(LoadCameraCalibration(path), 640, 480, 525.36, 526.10, 319.25, 241.12, dist);
  ExpectCamera(LoadOpenCvCalibration(path), 640, 480, 525.36, 526.10, 319.25, 241.12, dist);
}

TEST(CalibrationIo, ReadsOpenCvYamlWithoutHeader) {
  std::string text = kOpenCvYaml;
  text = text.substr(text.find("calibration_time"));
  const std::string path = WriteText(TestDir() / "calib.yml", text);
  ExpectCamera(LoadCameraCalibration(path), 640, 480, 525.36, 526.10, 319.25, 241.12,
               {0.15, -0.31, 0.0012, -0.0004, 0.11});
}

TEST(CalibrationIo, ReadsRosCameraInfo) {
  const std::string path = WriteText(TestDir() / "camera_info.yaml", kRosYaml);
  const std::vector<double> dist = {0.1, -0.2, 0.001, 0.002, 0.0};
  ExpectCamera(LoadCameraCalibration(path), 1280, 720, 911.5, 912.25, 640.2, 361.75, dist);
  ExpectCamera(LoadRosCameraInfo(path), 1280, 720, 911.5, 912.25, 640.2, 361.75, dist);
  // Message-style field names, no distortion.
  const std::string msg =
      WriteText(TestDir() / "msg.yaml",
                "height: 480\nwidth: 640\ndistortion_model: plumb_bob\n"
                "D: [0, 0, 0, 0, 0]\nK: [500, 0, 319.5, 0, 500, 239.5, 0, 0, 1]\n");
  ExpectCamera(LoadCameraCalibration(msg), 640, 480, 500, 500, 319.5, 239.5, {});
}

// As OpenCV writes XML (cv::FileStorage), with a matrix's values in one <data> element.
const char kOpenCvXml[] = R"(<?xml version="1.0"?>
<opencv_storage>
<image_width>640</image_width>
<image_height>480</image_height>
<camera_matrix type_id="opencv-matrix">
  <rows>3</rows>
  <cols>3</cols>
  <dt>d</dt>
  <data>
    5.2536e+02 0. 3.1925e+02 0. 5.2610e+02 2.4112e+02 0. 0. 1.</data></camera_matrix>
<distortion_coefficients type_id="opencv-matrix">
  <rows>5</rows>
  <cols>1</cols>
  <dt>d</dt>
  <data>
    1.5e-01 -3.1e-01 1.2e-03 -4.0e-04 1.1e-01</data></distortion_coefficients>
</opencv_storage>
)";

TEST(CalibrationIo, ReadsOpenCvXml) {
  const std::string path = WriteText(TestDir() / "calib.xml", kOpenCvXml);
  ExpectCamera(LoadCameraCalibration(path), 640, 480, 525.36, 526.10, 319.25, 241.12,
               {0.15, -0.31, 0.0012, -0.0004, 0.11});
  ExpectCamera(LoadOpenCvCalibration(path), 640, 480, 525.36, 526.10, 319.25, 241.12,
               {0.15, -0.31, 0.0012, -0.0004, 0.11});
}

// Inputs on which OpenCV's own readers (cv::FileStorage) hang or crash are refused with an
// error: a YAML mapping indented on its first line and followed by a line ending in '-'
// (OpenCV's parser loops forever looking for a next document), and a malformed XML
// declaration (its parser reads through a null pointer).
TEST(CalibrationIo, RejectsInputThatBreaksOpenCvsOwnReaders) {
  const fs::path dir = TestDir();
  const std::string second_document = "%YAML:1.0\n i: 1\nabc-\nc\n";
  ExpectError([&] { LoadOpenCvCalibration(WriteText(dir / "d.yaml", second_document)); },
              {"d.yaml", "\"image_width\"", "missing"});
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "e.yaml", second_document)); },
              {"e.yaml", "\"image_width\"", "missing"});
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "x.xml", "<?xml veon=")); },
              {"x.xml", "malformed OpenCV calibration file (XML)"});
  std::string wrong_root = kOpenCvXml;
  wrong_root = Replace(Replace(wrong_root, "<opencv_storage>", "<storage>"), "</opencv_storage>",
                       "</storage>");
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "r.xml", wrong_root)); },
              {"r.xml", "<storage>", "<opencv_storage>"});
  std::string short_data = kOpenCvXml;
  short_data = Replace(short_data, " 0. 0. 1.</data>", " 0. 0.</data>");
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "s.xml", short_data)); },
              {"s.xml", "\"camera_matrix\"", "8 values"});
}

TEST(CalibrationIo, WriteReadRoundTrip) {
  const fs::path dir = TestDir();
  PinholeCamera camera;
  camera.width = 512;
  camera.height = 256;
  camera.fx = 837.3;
  camera.fy = 836.9;
  camera.cx = 255.5;
  camera.cy = 127.25;
  camera.distortion = {-0.1, 0.05, 0.001, -0.002, 0.0, 0.01, 0.0, 0.002};
  for (const char* name : {"c.yaml", "c.xml", "c.json"}) {
    SCOPED_TRACE(name);
    const std::string path = (dir / name).string();
    SaveOpenCvCalibration(path, camera);
    ExpectCamera(LoadCameraCalibration(path), 512, 256, 837.3, 836.9, 255.5, 127.25,
                 camera.distortion);
  }
  camera.distortion.clear();
  SaveOpenCvCalibration((dir / "plain.yaml").string(), camera);
  const PinholeCamera back = LoadCameraCalibration((dir / "plain.yaml").string());
  EXPECT_TRUE(back.distortion.empty());
  // The written file is what OpenCV tools expect.
  cv::FileStorage fs((dir / "plain.yaml").string(), cv::FileStorage::READ);
  cv::Mat k;
  fs["camera_matrix"] >> k;
  EXPECT_EQ(k.rows, 3);
  EXPECT_DOUBLE_EQ(k.at<double>(0, 0), 837.3);
  EXPECT_EQ(static_cast<int>(fs["image_width"]), 512);
}

TEST(CalibrationIo, RejectsMissingKey) {
  const fs::path dir = TestDir();
  std::string text = kOpenCvYaml;
  text = Replace(text, "image_height: 480\n", "");
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "a.yaml", text)); },
              {"a.yaml", "\"image_height\"", "missing"});
  std::string ros = kRosYaml;
  ros = Replace(ros, "camera_matrix:", "cam_matrix:");
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "b.yaml", ros)); },
              {"b.yaml", "\"camera_matrix\"", "missing"});
}

TEST(CalibrationIo, RejectsWrongMatrixSize) {
  const fs::path dir = TestDir();
  std::string text = kOpenCvYaml;
  text = Replace(text, "rows: 3\n   cols: 3", "rows: 1\n   cols: 9");
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "a.yaml", text)); },
              {"a.yaml", "\"camera_matrix\"", "1x9", "3x3"});
  std::string ros = kRosYaml;
  ros = Replace(ros, "data: [911.5, 0, 640.2, 0, 912.25, 361.75, 0, 0, 1]",
                "data: [911.5, 0, 640.2, 0, 912.25, 361.75]");
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "b.yaml", ros)); },
              {"b.yaml", "\"camera_matrix\"", "6 values"});
  std::string dist = kRosYaml;
  dist = Replace(dist, "cols: 5\n  data: [0.1, -0.2, 0.001, 0.002, 0]",
                 "cols: 3\n  data: [0.1, -0.2, 0.001]");
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "c.yaml", dist)); },
              {"c.yaml", "distortion_coefficients", "3 values"});
}

TEST(CalibrationIo, RejectsNaN) {
  const fs::path dir = TestDir();
  std::string text = kOpenCvYaml;
  text = Replace(text, "5.2536e+02", ".nan");
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "a.yaml", text)); },
              {"a.yaml", "\"camera_matrix\"", "nan"});
  std::string ros = kRosYaml;
  ros = Replace(ros, "-0.2", ".nan");
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "b.yaml", ros)); },
              {"b.yaml", "\"distortion_coefficients\"", "nan"});
}

TEST(CalibrationIo, RejectsOtherBadInput) {
  const fs::path dir = TestDir();
  ExpectError([&] { LoadCameraCalibration((dir / "none.yaml").string()); },
              {"none.yaml", "not found"});
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "empty.yaml", "\n")); },
              {"empty.yaml", "empty"});
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "bad.yaml", "image_width: [640\n")); },
              {"bad.yaml", "malformed YAML"});
  std::string broken = kOpenCvYaml;
  broken = Replace(broken, "data: [ 1.5e-01", "data: [ [1.5e-01");
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "broken.yaml", broken)); },
              {"broken.yaml", "malformed OpenCV"});
  std::string fisheye = kRosYaml;
  fisheye = Replace(fisheye, "plumb_bob", "equidistant");
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "f.yaml", fisheye)); },
              {"f.yaml", "distortion_model", "equidistant"});
  std::string skew = kRosYaml;
  skew = Replace(skew, "[911.5, 0, 640.2", "[911.5, 3, 640.2");
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "s.yaml", skew)); },
              {"s.yaml", "camera_matrix", "skew"});
  std::string size = kRosYaml;
  size = Replace(size, "image_width: 1280", "image_width: wide");
  ExpectError([&] { LoadCameraCalibration(WriteText(dir / "w.yaml", size)); },
              {"w.yaml", "image_width", "wide"});
  PinholeCamera invalid;
  ExpectError([&] { SaveOpenCvCalibration((dir / "x.yaml").string(), invalid); }, {"x.yaml"});
}

}  // namespace
}  // namespace unseen
