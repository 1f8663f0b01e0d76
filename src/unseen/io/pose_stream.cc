// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/io/pose_stream.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "unseen/io/bop_json.h"
#include "unseen/util/error.h"
#include "unseen/util/files.h"

namespace unseen {

namespace {

constexpr const char* kColumns[] = {"frame", "time_s", "status", "confidence", "tx", "ty",
                                    "tz",    "qx",     "qy",     "qz",         "qw"};
constexpr double kQuaternionNormTolerance = 1e-3;

std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

std::string Trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const size_t e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> fields;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    fields.push_back(
        Trim(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return fields;
}

// Parses a whole field as a double (NaN/inf are parsed so that they can be reported).
double ParseDouble(const std::string& text, const std::string& what) {
  UNSEEN_CHECK(!text.empty(), "{}: value is empty, expected a number", what);
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  UNSEEN_CHECK(end == text.c_str() + text.size(), "{}: \"{}\" is not a number", what, text);
  return value;
}

// Checks a parsed record and builds its pose. `where` names file and line.
PoseRecord MakeRecord(double frame, double time_s, const std::string& status, double confidence,
                      const double t[3], const double q[4], std::optional<double> process_ms,
                      const std::string& where) {
  PoseRecord record;
  UNSEEN_CHECK(std::isfinite(frame) && frame >= 0 && frame == std::floor(frame) && frame < 2e9,
               "{}: field \"frame\" is {}, expected a non-negative integer", where, frame);
  record.frame = static_cast<int>(frame);
  UNSEEN_CHECK(std::isfinite(time_s), "{}: field \"time_s\" is {}, expected a finite number", where,
               time_s);
  record.time_s = time_s;
  record.status = ParseTrackStatus(status, where + ": field \"status\"");
  UNSEEN_CHECK(std::isfinite(confidence) && confidence >= 0.0 && confidence <= 1.0,
               "{}: field \"confidence\" is {}, expected a number in [0, 1]", where, confidence);
  record.confidence = confidence;
  const char* t_names[] = {"tx", "ty", "tz"};
  const char* q_names[] = {"qx", "qy", "qz", "qw"};
  for (int i = 0; i < 3; ++i) {
    UNSEEN_CHECK(std::isfinite(t[i]), "{}: field \"{}\" is {}, expected a finite number", where,
                 t_names[i], t[i]);
  }
  for (int i = 0; i < 4; ++i) {
    UNSEEN_CHECK(std::isfinite(q[i]), "{}: field \"{}\" is {}, expected a finite number", where,
                 q_names[i], q[i]);
  }
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  UNSEEN_CHECK(std::abs(norm - 1.0) <= kQuaternionNormTolerance,
               "{}: quaternion (qx, qy, qz, qw) = ({}, {}, {}, {}) has norm {:.6f}, expected 1",
               where, q[0], q[1], q[2], q[3], norm);
  record.world_from_obj =
      Rigid3d(Eigen::Quaterniond(q[3], q[0], q[1], q[2]), Eigen::Vector3d(t[0], t[1], t[2]));
  if (process_ms) {
    UNSEEN_CHECK(std::isfinite(*process_ms) && *process_ms >= 0.0,
                 "{}: field \"process_ms\" is {}, expected a non-negative number", where,
                 *process_ms);
  }
  record.process_ms = process_ms;
  return record;
}

std::vector<PoseRecord> ReadCsv(const std::string& path, std::istream& in) {
  std::string line;
  int line_number = 0;
  std::vector<std::string> header;
  while (header.empty() && std::getline(in, line)) {
    ++line_number;
    if (!Trim(line).empty()) header = SplitCsv(line);
  }
  UNSEEN_CHECK(!header.empty(), "{}: empty file, expected a CSV header line ({})", path,
               fmt::join(kColumns, ","));
  std::map<std::string, size_t> column;
  for (size_t i = 0; i < header.size(); ++i) column.emplace(header[i], i);
  for (const char* name : kColumns) {
    UNSEEN_CHECK(column.count(name), "{}:{}: header lacks column \"{}\" (header: {})", path,
                 line_number, name, line);
  }
  const auto process_it = column.find("process_ms");
  std::vector<PoseRecord> records;
  while (std::getline(in, line)) {
    ++line_number;
    if (Trim(line).empty()) continue;
    const std::string where = fmt::format("{}:{}", path, line_number);
    const std::vector<std::string> fields = SplitCsv(line);
    UNSEEN_CHECK(fields.size() == header.size(), "{}: {} fields, but the header has {} columns",
                 where, fields.size(), header.size());
    auto number = [&](const char* name) {
      return ParseDouble(fields[column.at(name)], fmt::format("{}: field \"{}\"", where, name));
    };
    const double t[3] = {number("tx"), number("ty"), number("tz")};
    const double q[4] = {number("qx"), number("qy"), number("qz"), number("qw")};
    std::optional<double> process_ms;
    if (process_it != column.end() && !fields[process_it->second].empty()) {
      process_ms =
          ParseDouble(fields[process_it->second], fmt::format("{}: field \"process_ms\"", where));
    }
    records.push_back(MakeRecord(number("frame"), number("time_s"), fields[column.at("status")],
                                 number("confidence"), t, q, process_ms, where));
  }
  return records;
}

std::vector<PoseRecord> ReadJsonLines(const std::string& path, std::istream& in) {
  std::string line;
  int line_number = 0;
  std::vector<PoseRecord> records;
  bool any_line = false;
  while (std::getline(in, line)) {
    ++line_number;
    if (Trim(line).empty()) continue;
    any_line = true;
    const std::string where = fmt::format("{}:{}", path, line_number);
    const nlohmann::json object = bop::ParseJson(line, where);
    UNSEEN_CHECK(object.is_object(), "{}: expected a JSON object per line", where);
    auto number = [&](const char* name) {
      const auto it = object.find(name);
      UNSEEN_CHECK(it != object.end(), "{}: field \"{}\" is missing", where, name);
      UNSEEN_CHECK(it->is_number(), "{}: field \"{}\" is {}, expected a finite number", where, name,
                   it->dump());
      return it->get<double>();
    };
    const auto status_it = object.find("status");
    UNSEEN_CHECK(status_it != object.end(), "{}: field \"status\" is missing", where);
    UNSEEN_CHECK(status_it->is_string(), "{}: field \"status\" is {}, expected a string", where,
                 status_it->dump());
    const double t[3] = {number("tx"), number("ty"), number("tz")};
    const double q[4] = {number("qx"), number("qy"), number("qz"), number("qw")};
    std::optional<double> process_ms;
    if (object.contains("process_ms") && !object["process_ms"].is_null()) {
      process_ms = number("process_ms");
    }
    records.push_back(MakeRecord(number("frame"), number("time_s"), status_it->get<std::string>(),
                                 number("confidence"), t, q, process_ms, where));
  }
  UNSEEN_CHECK(any_line, "{}: empty file, expected one JSON object per line", path);
  return records;
}

void CheckWritable(const PoseRecord& r, const std::string& path) {
  UNSEEN_CHECK(r.world_from_obj.IsValid(), "{}: frame {}: refusing to write invalid pose {}", path,
               r.frame, r.world_from_obj.ToString());
  UNSEEN_CHECK(std::isfinite(r.time_s) && std::isfinite(r.confidence),
               "{}: frame {}: time_s {} and confidence {} must be finite", path, r.frame, r.time_s,
               r.confidence);
}

}  // namespace

const char* ToString(TrackStatus status) {
  switch (status) {
    case TrackStatus::kTracking:
      return "tracking";
    case TrackStatus::kLost:
      return "lost";
    case TrackStatus::kSearching:
      return "searching";
  }
  return "unknown";
}

TrackStatus ParseTrackStatus(const std::string& text, const std::string& what) {
  if (text == "tracking") return TrackStatus::kTracking;
  if (text == "lost") return TrackStatus::kLost;
  if (text == "searching") return TrackStatus::kSearching;
  ThrowError("{}: unknown status \"{}\", expected tracking, lost or searching", what, text);
}

Rigid3d ParsePoseText(const std::string& text, const std::string& what) {
  std::vector<std::string> parts;
  for (size_t start = 0; start <= text.size();) {
    const size_t end = std::min(text.find(',', start), text.size());
    const size_t first = text.find_first_not_of(" \t\r\n", start);
    const size_t last = text.find_last_not_of(" \t\r\n", end - 1);
    parts.push_back(first < end && last != std::string::npos && last >= first
                        ? text.substr(first, last - first + 1)
                        : std::string());
    start = end + 1;
  }
  UNSEEN_CHECK(parts.size() == 7, "{}: '{}' must be seven numbers tx,ty,tz,qx,qy,qz,qw", what,
               text);
  double v[7];
  for (int i = 0; i < 7; ++i) {
    size_t used = 0;
    try {
      v[i] = std::stod(parts[i], &used);
    } catch (const std::exception&) {
      used = 0;
    }
    UNSEEN_CHECK(used > 0 && used == parts[i].size() && std::isfinite(v[i]),
                 "{}: value {} '{}' is not a finite number", what, i + 1, parts[i]);
  }
  const Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
  UNSEEN_CHECK(q.norm() > 1e-6, "{}: quaternion ({}, {}, {}, {}) is zero", what, v[3], v[4], v[5],
               v[6]);
  return Rigid3d(q.normalized(), Eigen::Vector3d(v[0], v[1], v[2]));
}

PoseStreamWriter::PoseStreamWriter(const std::string& path) : path_(path) {
  const std::string ext = LowerExtension(path);
  UNSEEN_CHECK(ext == ".csv" || ext == ".jsonl" || ext == ".json",
               "{}: unknown pose stream extension \"{}\", expected .csv, .jsonl or .json", path,
               ext);
  csv_ = ext == ".csv";
  out_ = std::make_unique<std::ofstream>(path);
  UNSEEN_CHECK(out_->good(), "{}: cannot create pose stream file", path);
  if (csv_) {
    *out_ << fmt::format("{},process_ms", fmt::join(kColumns, ",")) << '\n';
    out_->flush();
  }
}

PoseStreamWriter::~PoseStreamWriter() = default;

void PoseStreamWriter::Write(const PoseRecord& r) {
  CheckWritable(r, path_);
  const Eigen::Vector3d& t = r.world_from_obj.translation();
  const Eigen::Quaterniond& q = r.world_from_obj.rotation();
  if (csv_) {
    *out_ << fmt::format("{},{},{},{},{},{},{},{},{},{},{},{}\n", r.frame, r.time_s,
                         ToString(r.status), r.confidence, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(),
                         q.w(), r.process_ms ? fmt::format("{}", *r.process_ms) : "");
  } else {
    nlohmann::json line = {{"frame", r.frame},
                           {"time_s", r.time_s},
                           {"status", ToString(r.status)},
                           {"confidence", r.confidence},
                           {"tx", t.x()},
                           {"ty", t.y()},
                           {"tz", t.z()},
                           {"qx", q.x()},
                           {"qy", q.y()},
                           {"qz", q.z()},
                           {"qw", q.w()}};
    if (r.process_ms) line["process_ms"] = *r.process_ms;
    *out_ << line.dump() << '\n';
  }
  out_->flush();
  UNSEEN_CHECK(out_->good(), "{}: write failed at frame {}", path_, r.frame);
}

void WritePoseStream(const std::string& path, const std::vector<PoseRecord>& records) {
  PoseStreamWriter writer(path);
  for (const PoseRecord& r : records) writer.Write(r);
}

std::vector<PoseRecord> ReadPoseStream(const std::string& path) {
  UNSEEN_CHECK(IsFile(path), "{}: pose stream file not found", path);
  std::ifstream in(path);
  UNSEEN_CHECK(in.good(), "{}: cannot open pose stream file", path);
  // The format is told by the content: JSON lines start with '{', CSV with its header.
  char first = 0;
  while (in.get(first) && std::isspace(static_cast<unsigned char>(first))) {
  }
  UNSEEN_CHECK(in.good(), "{}: empty file, expected a CSV or JSON-lines pose stream", path);
  in.clear();
  in.seekg(0);
  std::vector<PoseRecord> records = first == '{' ? ReadJsonLines(path, in) : ReadCsv(path, in);
  std::set<int> seen;
  for (const PoseRecord& r : records) {
    UNSEEN_CHECK(seen.insert(r.frame).second, "{}: frame {} appears more than once", path, r.frame);
  }
  return records;
}

void ExportBopSceneGt(const std::string& path, const std::vector<PoseRecord>& records,
                      const Rigid3d& cam_from_world, int obj_id) {
  UNSEEN_CHECK(cam_from_world.IsValid(), "{}: invalid cam_from_world {}", path,
               cam_from_world.ToString());
  nlohmann::json gt = nlohmann::json::object();
  for (const PoseRecord& r : records) {
    if (r.status != TrackStatus::kTracking) continue;
    CheckWritable(r, path);
    nlohmann::json entry = {{"obj_id", obj_id}};
    bop::SetPoseMm(cam_from_world * r.world_from_obj, "cam_R_m2c", "cam_t_m2c", &entry);
    const std::string key = std::to_string(r.frame);
    UNSEEN_CHECK(!gt.contains(key), "{}: frame {} appears more than once", path, r.frame);
    gt[key] = nlohmann::json::array({entry});
  }
  bop::WriteJsonFile(path, gt, -1);
}

std::vector<PoseRecord> ReadBopSceneGtAsPoses(const std::string& path,
                                              const Rigid3d& world_from_cam, int obj_id,
                                              double fps) {
  UNSEEN_CHECK(std::isfinite(fps) && fps > 0.0, "{}: fps {} must be positive", path, fps);
  const nlohmann::json gt = bop::ReadJsonFile(path);
  UNSEEN_CHECK(gt.is_object(), "{}: expected a JSON object keyed by frame id", path);
  std::vector<PoseRecord> records;
  for (const auto& [key, list] : gt.items()) {
    const int frame = bop::ParseFrameId(key, path);
    const std::string what = fmt::format("{} frame {}", path, key);
    UNSEEN_CHECK(list.is_array(), "{}: expected a list of objects, got {}", what, list.dump());
    for (const nlohmann::json& entry : list) {
      const int id = bop::GetInt(entry, "obj_id", what);
      if (obj_id > 0 && id != obj_id) continue;
      if (obj_id <= 0) obj_id = id;  // the first object found, kept for every frame
      PoseRecord record;
      record.frame = frame;
      record.time_s = frame / fps;
      record.status = TrackStatus::kTracking;
      record.confidence = 1.0;
      record.world_from_obj =
          world_from_cam * bop::GetPoseMm(entry, "cam_R_m2c", "cam_t_m2c", what);
      records.push_back(record);
      break;
    }
  }
  std::sort(records.begin(), records.end(),
            [](const PoseRecord& a, const PoseRecord& b) { return a.frame < b.frame; });
  return records;
}

}  // namespace unseen
