// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/eval/sequence_poses.h"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "unseen/util/error.h"
#include "unseen/util/files.h"

namespace unseen {

std::vector<GroundTruthFrame> SequenceGroundTruth(const Sequence& sequence) {
  UNSEEN_CHECK(sequence.has_ground_truth(),
               "sequence '{}' has no ground truth (no scene_gt.json): cannot evaluate",
               sequence.path());
  std::vector<GroundTruthFrame> frames;
  frames.reserve(sequence.num_frames());
  for (int i = 0; i < sequence.num_frames(); ++i) {
    frames.push_back({sequence.frame_id(i), sequence.GroundTruth(i)});
  }
  return frames;
}

bool IsBopSceneGt(const std::string& path) {
  if (std::filesystem::path(path).extension() != ".json") return false;
  // A BOP scene_gt.json is one JSON object keyed by frame id; a JSON-lines stream of
  // several lines does not parse as one document, and a one-line stream is an object with
  // a "frame" key.
  std::ifstream in(path);
  const nlohmann::json doc = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  return !doc.is_discarded() && doc.is_object() && !doc.contains("frame");
}

std::vector<PoseRecord> ReadPosesForSequence(const std::string& path, const Sequence& sequence,
                                             const std::string& bop_camera) {
  namespace fs = std::filesystem;
  UNSEEN_CHECK(IsFile(path), "poses '{}': no such file", path);
  if (!IsBopSceneGt(path)) return ReadPoseStream(path);

  const Rig& rig = sequence.rig();
  int camera = sequence.reference_camera();
  if (!bop_camera.empty()) {
    camera = rig.Find(bop_camera);
    UNSEEN_CHECK(camera >= 0, "poses '{}': camera '{}' is not in the sequence '{}'", path,
                 bop_camera, sequence.path());
  } else {
    // A scene_gt.json inside the sequence's own camera folder is in that camera.
    std::error_code ec;
    const fs::path folder = fs::canonical(fs::path(path), ec).parent_path();
    const fs::path root = fs::canonical(fs::path(sequence.path()), ec);
    for (int i = 0; i < rig.size() && !ec; ++i) {
      if (folder.filename() == rig.cameras[i].name && folder.parent_path() == root) camera = i;
    }
  }
  UNSEEN_CHECK(camera >= 0 && camera < rig.size(),
               "poses '{}': no camera to place the BOP poses in (sequence '{}')", path,
               sequence.path());
  return ReadBopSceneGtAsPoses(path, rig.cameras[camera].world_from_cam, sequence.obj_id(),
                               sequence.fps());
}

}  // namespace unseen
