// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/io/bop_json.h"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <fmt/format.h>

#include "unseen/util/error.h"
#include "unseen/util/files.h"

namespace unseen::bop {

namespace {

// A short rendering of a JSON value for error messages.
std::string Brief(const nlohmann::json& value) {
  std::string text = value.dump();
  if (text.size() > 80) text = text.substr(0, 77) + "...";
  return text;
}

}  // namespace

nlohmann::json ParseJson(std::string_view text, const std::string& what) {
  const nlohmann::json::parser_callback_t limit_depth =
      [&what](int depth, nlohmann::json::parse_event_t, nlohmann::json&) {
        UNSEEN_CHECK(depth <= kMaxJsonDepth, "{}: JSON nested deeper than {} levels", what,
                     kMaxJsonDepth);
        return true;
      };
  try {
    return nlohmann::json::parse(text.begin(), text.end(), limit_depth);
  } catch (const nlohmann::json::exception& e) {
    ThrowError("{}: malformed JSON: {}", what, e.what());
  }
}

nlohmann::json ReadJsonFile(const std::string& path) {
  UNSEEN_CHECK(IsFile(path), "{}: file not found", path);
  std::ifstream in(path, std::ios::binary);
  UNSEEN_CHECK(in.good(), "{}: cannot open file", path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  UNSEEN_CHECK(!in.bad(), "{}: cannot read file", path);
  return ParseJson(text, path);
}

namespace {

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  UNSEEN_CHECK(out.good(), "{}: cannot create file", path);
  out << text << '\n';
  out.close();
  UNSEEN_CHECK(out.good(), "{}: write failed", path);
}

}  // namespace

void WriteJsonFile(const std::string& path, const nlohmann::json& json, int indent) {
  WriteText(path, json.dump(indent));
}

void WriteJsonFile(const std::string& path, const nlohmann::ordered_json& json, int indent) {
  WriteText(path, json.dump(indent));
}

int ParseFrameId(const std::string& key, const std::string& what) {
  int id = -1;
  const char* end = key.data() + key.size();
  const auto [ptr, ec] = std::from_chars(key.data(), end, id);
  UNSEEN_CHECK(!key.empty() && ec == std::errc() && ptr == end && id >= 0,
               "{}: frame id \"{}\" is not a non-negative integer", what, key);
  return id;
}

std::vector<double> GetNumbers(const nlohmann::json& object, const std::string& key, size_t size,
                               const std::string& what) {
  UNSEEN_CHECK(object.is_object(), "{}: expected a JSON object, got {}", what, Brief(object));
  const auto it = object.find(key);
  UNSEEN_CHECK(it != object.end(), "{}: field \"{}\" is missing", what, key);
  UNSEEN_CHECK(it->is_array(), "{}: field \"{}\" must be an array of {} numbers, got {}", what, key,
               size, Brief(*it));
  UNSEEN_CHECK(it->size() == size, "{}: field \"{}\" has {} values, expected {}: {}", what, key,
               it->size(), size, Brief(*it));
  std::vector<double> values;
  values.reserve(size);
  for (size_t i = 0; i < size; ++i) {
    const nlohmann::json& v = (*it)[i];
    UNSEEN_CHECK(v.is_number(), "{}: field \"{}\" value {} is {}, expected a finite number", what,
                 key, i, Brief(v));
    const double d = v.get<double>();
    UNSEEN_CHECK(std::isfinite(d), "{}: field \"{}\" value {} is {}, expected a finite number",
                 what, key, i, d);
    values.push_back(d);
  }
  return values;
}

double GetNumber(const nlohmann::json& object, const std::string& key, const std::string& what) {
  UNSEEN_CHECK(object.is_object(), "{}: expected a JSON object, got {}", what, Brief(object));
  const auto it = object.find(key);
  UNSEEN_CHECK(it != object.end(), "{}: field \"{}\" is missing", what, key);
  UNSEEN_CHECK(it->is_number(), "{}: field \"{}\" is {}, expected a finite number", what, key,
               Brief(*it));
  const double d = it->get<double>();
  UNSEEN_CHECK(std::isfinite(d), "{}: field \"{}\" is {}, expected a finite number", what, key, d);
  return d;
}

int GetInt(const nlohmann::json& object, const std::string& key, const std::string& what) {
  UNSEEN_CHECK(object.is_object(), "{}: expected a JSON object, got {}", what, Brief(object));
  const auto it = object.find(key);
  UNSEEN_CHECK(it != object.end(), "{}: field \"{}\" is missing", what, key);
  UNSEEN_CHECK(it->is_number_integer(), "{}: field \"{}\" is {}, expected an integer", what, key,
               Brief(*it));
  return it->get<int>();
}

Rigid3d GetPoseMm(const nlohmann::json& object, const std::string& rotation_key,
                  const std::string& translation_key, const std::string& what) {
  const std::vector<double> r = GetNumbers(object, rotation_key, 9, what);
  const std::vector<double> t = GetNumbers(object, translation_key, 3, what);
  Eigen::Matrix3d rotation;
  rotation << r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8];
  const Eigen::Vector3d translation_m = Eigen::Vector3d(t[0], t[1], t[2]) * 1e-3;
  return Rigid3d::FromRotationMatrix(rotation, translation_m,
                                     fmt::format("{}: field \"{}\"", what, rotation_key));
}

void SetPoseMm(const Rigid3d& pose, const std::string& rotation_key,
               const std::string& translation_key, nlohmann::json* object) {
  const Eigen::Matrix3d r = pose.RotationMatrix();
  const Eigen::Vector3d t = pose.translation() * 1e3;
  (*object)[rotation_key] = {r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1),
                             r(1, 2), r(2, 0), r(2, 1), r(2, 2)};
  (*object)[translation_key] = {t.x(), t.y(), t.z()};
}

std::string FrameName(int frame_id) { return fmt::format("{:06d}", frame_id); }

}  // namespace unseen::bop
