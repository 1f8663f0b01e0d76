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
#include <pugixml.hpp>
#include <sstream>
#include <string_view>
#include <vector>

#include "unseen/util/error.h"
#include "unseen/util/files.h"

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

// --- Text formats into one tree ------------------------------------------------------
//
// cv::FileStorage does not read outside files here: fuzzing found its YAML parser looping
// forever once a first document ends early and what follows starts with '-', its XML parser
// reading through a null pointer on a malformed declaration, and both exhausting the stack
// on deep nesting. YAML and JSON (which YAML reads) go through yaml-cpp, XML through
// pugixml, into one YAML::Node tree that ReadFields checks field by field.

constexpr int kMaxNesting = 64;  // a calibration file nests a few levels

// yaml-cpp (and any parser that recurses per level) would exhaust the stack on deeply
// nested input. Counts [ ], { } and XML elements.
void CheckNesting(const std::string& path, const std::string& text) {
  int depth = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    const char next = i + 1 < text.size() ? text[i + 1] : '\0';
    if (c == '[' || c == '{' || (c == '<' && std::isalpha(static_cast<unsigned char>(next)))) {
      ++depth;
    } else if (c == ']' || c == '}' || (c == '<' && next == '/') || (c == '/' && next == '>')) {
      --depth;
    }
    UNSEEN_CHECK(depth <= kMaxNesting, "{}: nested deeper than {} levels (at byte {})", path,
                 kMaxNesting, i);
  }
}

// A text format never holds a NUL byte.
void CheckText(const std::string& path, const std::string& text) {
  const size_t nul = text.find('\0');
  UNSEEN_CHECK(nul == std::string::npos, "{}: binary data (a NUL byte at byte {}) in a text file",
               path, nul);
  CheckNesting(path, text);
}

// OpenCV's YAML starts with a `%YAML:1.0` directive, which is not YAML 1.2 syntax; its
// directive lines become comments (keeping the line numbers of parse errors).
std::string WithoutYamlDirectives(const std::string& text) {
  std::string out;
  out.reserve(text.size() + 16);
  size_t begin = 0;
  while (begin < text.size()) {
    size_t end = text.find('\n', begin);
    end = end == std::string::npos ? text.size() : end + 1;
    if (text.compare(begin, 5, "%YAML") == 0) out += '#';
    out.append(text, begin, end - begin);
    begin = end;
  }
  return out;
}

YAML::Node ParseYaml(const std::string& path, const std::string& text, const char* kind) {
  try {
    return YAML::Load(WithoutYamlDirectives(text));
  } catch (const YAML::Exception& e) {
    ThrowError("{}: malformed {}: {}", path, kind, e.what());
  }
}

// An XML element as OpenCV writes it: child elements make a map by name (<_> items a
// sequence), text alone a scalar, or a sequence when it holds several whitespace-separated
// values (a matrix's <data>).
YAML::Node XmlToYaml(const pugi::xml_node& element, int depth, const std::string& path) {
  UNSEEN_CHECK(depth <= kMaxNesting, "{}: XML nested deeper than {} levels", path, kMaxNesting);
  bool has_elements = false, has_items = false;
  for (const pugi::xml_node& child : element.children()) {
    if (child.type() != pugi::node_element) continue;
    has_elements = true;
    has_items = has_items || std::string_view(child.name()) == "_";
  }
  if (has_elements) {
    YAML::Node node(has_items ? YAML::NodeType::Sequence : YAML::NodeType::Map);
    for (const pugi::xml_node& child : element.children()) {
      if (child.type() != pugi::node_element) continue;
      if (has_items) {
        if (std::string_view(child.name()) == "_")
          node.push_back(XmlToYaml(child, depth + 1, path));
      } else {
        node[child.name()] = XmlToYaml(child, depth + 1, path);
      }
    }
    return node;
  }
  std::vector<std::string> values;
  std::istringstream words(element.text().get());
  for (std::string word; words >> word;) values.push_back(word);
  if (values.empty()) return YAML::Node();
  if (values.size() == 1) return YAML::Node(values.front());
  YAML::Node sequence(YAML::NodeType::Sequence);
  for (const std::string& v : values) sequence.push_back(v);
  return sequence;
}

YAML::Node ParseOpenCvXml(const std::string& path, const std::string& text) {
  pugi::xml_document document;
  const pugi::xml_parse_result parsed =
      document.load_buffer(text.data(), text.size(), pugi::parse_default, pugi::encoding_utf8);
  UNSEEN_CHECK(parsed, "{}: malformed OpenCV calibration file (XML): {} at byte {}", path,
               parsed.description(), parsed.offset);
  const pugi::xml_node root = document.document_element();
  UNSEEN_CHECK(std::string_view(root.name()) == "opencv_storage",
               "{}: the XML root element is <{}>, expected <opencv_storage>", path, root.name());
  return XmlToYaml(root, 0, path);
}

// An OpenCV file (YAML, JSON or XML, told apart by its first character) as a tree.
YAML::Node ParseOpenCv(const std::string& path, const std::string& text) {
  CheckText(path, text);
  if (LeftTrimmed(text).rfind('<', 0) == 0) return ParseOpenCvXml(path, text);
  return ParseYaml(path, text, "OpenCV calibration file (YAML/JSON)");
}

// A ROS camera_info file (YAML) as a tree.
YAML::Node ParseRos(const std::string& path, const std::string& text) {
  CheckText(path, text);
  return ParseYaml(path, text, "YAML");
}

// --- Fields -----------------------------------------------------------------------------

YAML::Node Field(const YAML::Node& root, std::initializer_list<const char*> keys,
                 const std::string& path, bool required) {
  for (const char* key : keys) {
    if (root[key]) return root[key];
  }
  UNSEEN_CHECK(!required, "{}: field \"{}\" is missing", path, *keys.begin());
  return YAML::Node();  // null: absent
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

// The fields of either layout: OpenCV's (image_width, camera_matrix {rows, cols, dt, data},
// distortion_coefficients) and ROS camera_info's (the same names and distortion_model, or the
// message's width, K, D).
PinholeCamera ReadFields(const YAML::Node& root, const std::string& path) {
  UNSEEN_CHECK(root.IsMap(), "{}: expected a mapping of calibration fields", path);
  const int width = YamlInt(Field(root, {"image_width", "width"}, path, true), "image_width", path);
  const int height =
      YamlInt(Field(root, {"image_height", "height"}, path, true), "image_height", path);
  const std::vector<double> k =
      YamlMatrix(Field(root, {"camera_matrix", "K", "k"}, path, true), "camera_matrix", path, 3, 3);
  const YAML::Node model_node = Field(root, {"distortion_model"}, path, false);
  std::string model = "plumb_bob";
  if (model_node && !model_node.IsNull()) {
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
  return ReadFields(ParseOpenCv(path, ReadText(path)), path);
}

PinholeCamera LoadRosCameraInfo(const std::string& path) {
  return ReadFields(ParseRos(path, ReadText(path)), path);
}

PinholeCamera LoadCameraCalibration(const std::string& path) {
  const std::string text = ReadText(path);
  const std::string trimmed = LeftTrimmed(text);
  UNSEEN_CHECK(!trimmed.empty(), "{}: calibration file is empty", path);
  const bool opencv = trimmed.rfind("%YAML", 0) == 0 || trimmed.rfind("<", 0) == 0 ||
                      text.find("opencv-matrix") != std::string::npos;
  return ReadFields(opencv ? ParseOpenCv(path, text) : ParseRos(path, text), path);
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
