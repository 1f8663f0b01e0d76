// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Pose streams (DATASET.md "Output"): one record per frame with T_world_object in metres
// and a unit quaternion, as CSV with a header or JSON lines, chosen by file extension
// (.csv / .jsonl). Columns: frame, time_s, status, confidence, tx, ty, tz, qx, qy, qz, qw,
// and optionally process_ms (wall-clock processing time of the frame) which gives fps.
#pragma once

#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "unseen/geometry/rigid3.h"

namespace unseen {

enum class TrackStatus { kTracking, kLost, kSearching };
const char* ToString(TrackStatus status);  // "tracking", "lost", "searching"
// Throws unseen::Error naming `what` for any other string.
TrackStatus ParseTrackStatus(const std::string& text, const std::string& what = "status");

struct PoseRecord {
  int frame = 0;
  double time_s = 0.0;  // frame time from the sequence start, seconds
  TrackStatus status = TrackStatus::kTracking;
  double confidence = 1.0;  // [0, 1]
  Rigid3d world_from_obj;
  std::optional<double> process_ms;  // processing time of this frame, if measured
};

// Writes records one at a time (flushed per record, so a killed run keeps its poses).
class PoseStreamWriter {
 public:
  // Format by extension: .csv or .jsonl/.json. Throws unseen::Error if the file cannot be
  // created or the extension is unknown.
  explicit PoseStreamWriter(const std::string& path);
  ~PoseStreamWriter();
  void Write(const PoseRecord& record);

 private:
  std::string path_;
  bool csv_ = true;
  std::unique_ptr<std::ofstream> out_;
};

void WritePoseStream(const std::string& path, const std::vector<PoseRecord>& records);

// Reads a CSV or JSON-lines stream. Throws unseen::Error naming the file, line and field
// for a malformed line, NaN value or non-unit quaternion (|q| off by more than 1e-3).
std::vector<PoseRecord> ReadPoseStream(const std::string& path);

// BOP scene_gt.json export: model->camera poses in millimetres for camera `cam_from_world`,
// one object `obj_id` per frame. Lost frames are omitted (BOP has no status field).
void ExportBopSceneGt(const std::string& path, const std::vector<PoseRecord>& records,
                      const Rigid3d& cam_from_world, int obj_id);

}  // namespace unseen
