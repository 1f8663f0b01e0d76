// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Inputs of the evaluation taken from a sequence: its ground truth, and the poses to score
// read from a pose stream or a BOP scene_gt.json placed in the sequence's world frame.
#pragma once

#include <string>
#include <vector>

#include "unseen/eval/evaluation.h"
#include "unseen/io/pose_stream.h"
#include "unseen/io/sequence.h"

namespace unseen {

// The ground truth of every frame of `sequence` (Sequence::GroundTruth). Throws
// unseen::Error naming the sequence when it has no ground truth at all.
std::vector<GroundTruthFrame> SequenceGroundTruth(const Sequence& sequence);

// True when `path` is a .json file holding one JSON object keyed by frame id (a BOP
// scene_gt.json) rather than a JSON-lines pose stream.
bool IsBopSceneGt(const std::string& path);

// Reads the poses to score: a pose stream (.csv, .jsonl, or a .json file of JSON lines)
// or a BOP scene_gt.json (model->camera, millimetres) for the sequence's object id, placed
// in the world frame through the extrinsics of camera `bop_camera` (a rig camera name);
// empty `bop_camera` means the camera whose folder in the sequence holds the file, else
// the reference camera. Throws unseen::Error for a missing or malformed file or an unknown
// camera.
std::vector<PoseRecord> ReadPosesForSequence(const std::string& path, const Sequence& sequence,
                                             const std::string& bop_camera = "");

}  // namespace unseen
