// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/camera/calibration_io.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <sstream>

#include "unseen/util/error.h"
#include "unseen/util/files.h"
#include "unseen/util/yaml_options.h"

namespace unseen {

namespace {

std::string ReadText(const std::string& path) {
  UNSEEN_CHECK(IsFile(path), "{}: calibration file not found", path);
  std::ifstream in(path, std::ios::binary);
  UNSEEN_CHECK(in.good(), "{}: cannot open calibration file", path);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

std::string LeftTrimmed(const std::string& text) {
  const size_t b = text.find_first_not_of(" \t\r\n\xEF\xBB\xBF");
  return b == std::string::npos ? "" : text.substr(b);
}

// Builds the camera from a row-major 3x3 K, size and distortion, with every check.
PinholeCamera MakeCamera(const std::vector<double>& k, int width, int height,
                         const std::vector<double>& distortion, const std::string& path) {
  for (size_t i = 0; i < k.size(); ++i) {
    UNSEEN_CHECK(std::isfinite(k[i]), "{}: field \"camera_matrix\" value {} is {}", path, i, k[i]);
  }
  for (size_t i = 0; i < distortion.size(); ++i) {
    UNSEEN_CHECK(std::isfinite(distortion[i]),
                 "{}: field \"distortion_coefficients\" value {} is {}", path, i, distortion[i]);
  }
  UNSEEN_CHECK(std::abs(k[1]) <= 1e-9 * std::abs(k[0]) && k[3] == 0.0 && k[6] == 0.0 &&
                   k[7] == 0.0 && std::abs(k[8] - 1.0) < 1e-12,
               "{}: field \"camera_matrix\" = [{}] is not [fx 0 cx; 0 fy cy; 0 0 1] (skew is "
               "not supported)",
               path, fmt::join(k, ", "));
  PinholeCamera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = k[0];
  camera.cx = k[2];
  camera.fy = k[4];
  camera.cy = k[5];
  if (std::any_of(distortion.begin(), distortion.end(), [](double d) { return d != 0.0; })) {
    camera.distortion = distortion;
  }
  const size_t n = distortion.size();
  UNSEEN_CHECK(n == 0 || n == 4 || n == 5 || n == 8 || n == 12 || n == 14,
               "{}: field \"distortion_coefficients\" has {} values; OpenCV takes 4, 5, 8, 12 "
               "or 14",
               path, n);
  camera.Check(path);
  return camera;
}

// --- OpenCV (cv::FileStorage) -----------------------------------------------------------

int ReadInt(const cv::FileStorage& fs, const char* key, const std::string& path) {
  const cv::FileNode node = fs[key];
  UNSEEN_CHECK(!node.empty() && !node.isNone(), "{}: field \"{}\" is missing", path, key);
  UNSEEN_CHECK(node.isInt(), "{}: field \"{}\" must be an integer", path, key);
  return static_cast<int>(node);
}

// cv::read allocates the matrix that "rows" and "cols" (or an n-d matrix's "sizes") declare
// before it reads "data", so a declared shape larger than any calibration matrix is rejected
// first.
void CheckMatrixShape(const cv::FileNode& node, const char* key, const std::string& path) {
  constexpr int kMaxSide = 64;
  UNSEEN_CHECK(node.isMap(), "{}: field \"{}\" is not a matrix (rows, cols, dt, data)", path, key);
  std::vector<cv::FileNode> sides = {node["rows"], node["cols"]};
  const cv::FileNode sizes = node["sizes"];
  if (!sizes.empty() && !sizes.isNone()) {
    UNSEEN_CHECK(sizes.isSeq() && sizes.size() <= 2,
                 "{}: field \"{}\" has \"sizes\" of a matrix of more than 2 dimensions", path, key);
    for (size_t i = 0; i < sizes.size(); ++i) sides.push_back(sizes[static_cast<int>(i)]);
  }
  for (const cv::FileNode& side : sides) {
    if (side.empty() || side.isNone()) continue;
    UNSEEN_CHECK(side.isInt(), "{}: field \"{}\" has a size \"{}\" that is not an integer", path,
                 key, side.isString() ? side.string() : std::string("(not a number)"));
    const int n = static_cast<int>(side);
    UNSEEN_CHECK(n >= 0 && n <= kMaxSide,
                 "{}: field \"{}\" declares a size of {}, expected at most {}", path, key, n,
                 kMaxSide);
  }
}

std::vector<double> ReadMatrix(const cv::FileStorage& fs, const char* key, const std::string& path,
                               bool required, int rows, int cols) {
  const cv::FileNode node = fs[key];
  if (node.empty() || node.isNone()) {
    UNSEEN_CHECK(!required, "{}: field \"{}\" is missing", path, key);
    return {};
  }
  CheckMatrixShape(node, key, path);
  cv::Mat m;
  node >> m;
  UNSEEN_CHECK(!m.empty() && m.channels() == 1, "{}: field \"{}\" is not a matrix", path, key);
  if (rows > 0) {
    UNSEEN_CHECK(m.rows == rows && m.cols == cols, "{}: field \"{}\" is {}x{}, expected {}x{}",
                 path, key, m.rows, m.cols, rows, cols);
  } else {
    UNSEEN_CHECK(m.rows == 1 || m.cols == 1, "{}: field \"{}\" is {}x{}, expected a vector", path,
                 key, m.rows, m.cols);
  }
  cv::Mat d;
  m.convertTo(d, CV_64F);
  d = d.reshape(1, 1);
  return std::vector<double>(d.begin<double>(), d.end<double>());
}

PinholeCamera ReadOpenCv(cv::FileStorage& fs, const std::string& path) {
  const std::vector<double> k = ReadMatrix(fs, "camera_matrix", path, true, 3, 3);
  const std::vector<double> dist = ReadMatrix(fs, "distortion_coefficients", path, false, -1, -1);
  const int width = ReadInt(fs, "image_width", path);
  const int height = ReadInt(fs, "image_height", path);
  return MakeCamera(k, width, height, dist, path);
}

// cv::FileStorage parses recursively, so that deeply nested input exhausts the stack; a
// calibration file nests a few levels. Counts [ ], { } and XML elements.
void CheckNesting(const std::string& path, const std::string& text) {
  constexpr int kMaxDepth = 64;
  int depth = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    const char next = i + 1 < text.size() ? text[i + 1] : '\0';
    if (c == '[' || c == '{' || (c == '<' && std::isalpha(static_cast<unsigned char>(next)))) {
      ++depth;
    } else if (c == ']' || c == '}' || (c == '<' && next == '/') || (c == '/' && next == '>')) {
      --depth;
    }
    UNSEEN_CHECK(depth <= kMaxDepth, "{}: nested deeper than {} levels (at byte {})", path,
                 kMaxDepth, i);
  }
}

PinholeCamera LoadOpenCvText(const std::string& path, const std::string& text) {
  // A text format never holds a NUL byte; OpenCV 4.6's XML parser reads through a null
  // pointer on some that do.
  const size_t nul = text.find('\0');
  UNSEEN_CHECK(nul == std::string::npos, "{}: binary data (a NUL byte at byte {}) in a text file",
               path, nul);
  CheckNesting(path, text);
  try {
    std::string content = text;
    const std::string trimmed = LeftTrimmed(text);
    const bool yaml_without_header =
        trimmed.rfind("%YAML", 0) != 0 && trimmed.rfind("<", 0) != 0 && trimmed.rfind("{", 0) != 0;
    // cv::FileStorage needs the %YAML:1.0 header that OpenCV writes; hand-written files
    // often lack it.
    if (yaml_without_header) content = "%YAML:1.0\n" + trimmed;
    cv::FileStorage fs(content, cv::FileStorage::READ | cv::FileStorage::MEMORY);
    UNSEEN_CHECK(fs.isOpened(), "{}: not an OpenCV YAML/XML/JSON file", path);
    return ReadOpenCv(fs, path);
  } catch (const Error&) {
    throw;
  } catch (const cv::Exception& e) {
    ThrowError("{}: malformed OpenCV calibration file: {}", path, e.what());
  } catch (const std::exception& e) {
    // OpenCV 4.6's YAML parser also throws std::length_error on some malformed keys.
    ThrowError("{}: malformed OpenCV calibration file: {}", path, e.what());
  }
}

// --- ROS camera_info (yaml-cpp) ------------------------------------------------------

YAML::Node Field(const YAML::Node& root, std::initializer_list<const char*> keys,
                 const std::string& path, bool required) {
  for (const char* key : keys) {
    if (root[key]) return root[key];
  }
  UNSEEN_CHECK(!required, "{}: field \"{}\" is missing", path, *keys.begin());
  return YAML::Node();
}

int YamlInt(const YAML::Node& node, const std::string& key, const std::string& path) {
  try {
    return node.as<int>();
  } catch (const YAML::Exception&) {
    ThrowError("{}: field \"{}\" is \"{}\", expected an integer", path, key,
               node.IsScalar() ? node.Scalar() : "(not a scalar)");
  }
}

std::vector<double> YamlNumbers(const YAML::Node& node, const std::string& key,
                                const std::string& path) {
  UNSEEN_CHECK(node.IsSequence(), "{}: field \"{}\" must be a list of numbers", path, key);
  std::vector<double> values;
  for (size_t i = 0; i < node.size(); ++i) {
    try {
      values.push_back(node[i].as<double>());
    } catch (const YAML::Exception&) {
      ThrowError("{}: field \"{}\" value {} is \"{}\", expected a number", path, key, i,
                 node[i].IsScalar() ? node[i].Scalar() : "(not a scalar)");
    }
  }
  return values;
}

// A matrix given as {rows, cols, data} or as a plain list (message style).
std::vector<double> YamlMatrix(const YAML::Node& node, const std::string& key,
                               const std::string& path, int rows, int cols) {
  if (node.IsSequence()) {
    std::vector<double> values = YamlNumbers(node, key, path);
    if (rows > 0) {
      UNSEEN_CHECK(static_cast<int>(values.size()) == rows * cols,
                   "{}: field \"{}\" has {} values, expected {}", path, key, values.size(),
                   rows * cols);
    }
    return values;
  }
  UNSEEN_CHECK(node.IsMap(), "{}: field \"{}\" must be {{rows, cols, data}}", path, key);
  UNSEEN_CHECK(node["data"], "{}: field \"{}.data\" is missing", path, key);
  std::vector<double> values = YamlNumbers(node["data"], key + ".data", path);
  const int r = node["rows"] ? YamlInt(node["rows"], key + ".rows", path) : -1;
  const int c = node["cols"] ? YamlInt(node["cols"], key + ".cols", path) : -1;
  if (r >= 0 && c >= 0) {
    UNSEEN_CHECK(static_cast<size_t>(r) * c == values.size(),
                 "{}: field \"{}\" is {}x{} but has {} values", path, key, r, c, values.size());
  }
  if (rows > 0) {
    UNSEEN_CHECK((r < 0 || r == rows) && (c < 0 || c == cols) &&
                     static_cast<int>(values.size()) == rows * cols,
                 "{}: field \"{}\" is {}x{} with {} values, expected {}x{}", path, key, r, c,
                 values.size(), rows, cols);
  }
  return values;
}

PinholeCamera ReadRos(const YAML::Node& root, const std::string& path) {
  UNSEEN_CHECK(root.IsMap(), "{}: expected a YAML mapping (ROS camera_info)", path);
  const int width = YamlInt(Field(root, {"image_width", "width"}, path, true), "image_width", path);
  const int height =
      YamlInt(Field(root, {"image_height", "height"}, path, true), "image_height", path);
  const std::vector<double> k =
      YamlMatrix(Field(root, {"camera_matrix", "K", "k"}, path, true), "camera_matrix", path, 3, 3);
  const YAML::Node model_node = Field(root, {"distortion_model"}, path, false);
  std::string model = "plumb_bob";
  if (model_node) {
    UNSEEN_CHECK(model_node.IsScalar(), "{}: field \"distortion_model\" must be a string", path);
    model = model_node.Scalar();
  }
  UNSEEN_CHECK(model == "plumb_bob" || model == "rational_polynomial" || model.empty(),
               "{}: field \"distortion_model\" is \"{}\"; only plumb_bob and rational_polynomial "
               "(OpenCV's model) are supported",
               path, model);
  std::vector<double> dist;
  const YAML::Node dist_node = Field(root, {"distortion_coefficients", "D", "d"}, path, false);
  if (dist_node && !dist_node.IsNull()) {
    dist = YamlMatrix(dist_node, "distortion_coefficients", path, -1, -1);
  }
  return MakeCamera(k, width, height, dist, path);
}

}  // namespace

PinholeCamera LoadOpenCvCalibration(const std::string& path) {
  return LoadOpenCvText(path, ReadText(path));
}

PinholeCamera LoadRosCameraInfo(const std::string& path) {
  const std::string text = ReadText(path);
  const YAML::Node root = ParseYamlText(text, path);
  return ReadRos(root, path);
}

PinholeCamera LoadCameraCalibration(const std::string& path) {
  const std::string text = ReadText(path);
  const std::string trimmed = LeftTrimmed(text);
  UNSEEN_CHECK(!trimmed.empty(), "{}: calibration file is empty", path);
  const bool opencv = trimmed.rfind("%YAML", 0) == 0 || trimmed.rfind("<", 0) == 0 ||
                      text.find("opencv-matrix") != std::string::npos;
  if (opencv) return LoadOpenCvText(path, text);
  return LoadRosCameraInfo(path);
}

void SaveOpenCvCalibration(const std::string& path, const PinholeCamera& camera) {
  camera.Check(path);
  try {
    cv::FileStorage fs(path, cv::FileStorage::WRITE);
    UNSEEN_CHECK(fs.isOpened(), "{}: cannot create calibration file", path);
    fs << "image_width" << camera.width;
    fs << "image_height" << camera.height;
    const cv::Mat k = (cv::Mat_<double>(3, 3) << camera.fx, 0.0, camera.cx, 0.0, camera.fy,
                       camera.cy, 0.0, 0.0, 1.0);
    fs << "camera_matrix" << k;
    std::vector<double> dist = camera.distortion;
    if (dist.empty()) dist.assign(5, 0.0);
    fs << "distortion_coefficients"
       << cv::Mat(dist, true).reshape(1, static_cast<int>(dist.size()));
    fs.release();
  } catch (const cv::Exception& e) {
    ThrowError("{}: cannot write calibration file: {}", path, e.what());
  }
  UNSEEN_CHECK(IsFile(path), "{}: calibration file was not written",
               path);
}

}  // namespace unseen
