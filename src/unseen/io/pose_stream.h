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
// A pose written as seven comma-separated numbers "tx,ty,tz,qx,qy,qz,qw" (metres, a
// quaternion of any non-zero norm, normalised), blanks around them allowed (a file's
// trailing newline). Throws unseen::Error naming `what` and the offending value.
Rigid3d ParsePoseText(const std::string& text, const std::string& what);

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
  // created or the extension is unknown. Numbers are written with round-trip precision;
  // the CSV always has the process_ms column (empty when a record has no timing).
  explicit PoseStreamWriter(const std::string& path);
  ~PoseStreamWriter();
  // Throws unseen::Error naming the file and frame for a non-finite pose/time/confidence.
  void Write(const PoseRecord& record);

 private:
  std::string path_;
  bool csv_ = true;
  std::unique_ptr<std::ofstream> out_;
};

// Writes all `records` to `path` with a PoseStreamWriter (same format and errors).
void WritePoseStream(const std::string& path, const std::vector<PoseRecord>& records);

// Reads a CSV or JSON-lines stream (told apart by content, not extension). CSV needs a
// header naming the columns above in any order; process_ms may be absent (or empty per
// line) and unknown extra columns/fields are ignored. Throws unseen::Error naming the file,
// line and field for an empty file, a missing column, a malformed line, NaN value, unknown
// status, confidence outside [0, 1], non-unit quaternion (|q| off by more than 1e-3; the
// quaternion is then normalised) or a frame number given twice.
std::vector<PoseRecord> ReadPoseStream(const std::string& path);

// BOP scene_gt.json export: model->camera poses in millimetres for camera `cam_from_world`,
// one object `obj_id` per frame. Frames without a tracked pose (status lost or searching)
// are omitted (BOP has no status field). Throws unseen::Error for an invalid pose or an
// unwritable file.
void ExportBopSceneGt(const std::string& path, const std::vector<PoseRecord>& records,
                      const Rigid3d& cam_from_world, int obj_id);

// Reads a BOP scene_gt.json (model->camera, millimetres) as a pose stream so that it can be
// scored like one: per frame id that holds object `obj_id` (obj_id <= 0: the first object
// id found), a record with world_from_obj = world_from_cam * cam_from_obj in metres,
// time_s = frame / fps, status tracking, confidence 1, no process_ms. Frames without the
// object are absent. Sorted by frame. Throws unseen::Error naming file, frame and field for
// malformed JSON, a missing/short field, NaN or a non-orthonormal rotation.
std::vector<PoseRecord> ReadBopSceneGtAsPoses(const std::string& path,
                                              const Rigid3d& world_from_cam, int obj_id,
                                              double fps);

}  // namespace unseen
