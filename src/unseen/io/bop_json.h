// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Helpers for the BOP JSON files of DATASET.md (scene_camera.json, scene_gt.json,
// sequence.json): strict field access whose errors name the file, the field, the frame
// and the value, and the millimetre <-> metre pose conversions. Used by sequence.cc and
// pose_stream.cc; not part of the public io interface.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "unseen/geometry/rigid3.h"

namespace unseen::bop {

// Nesting depth that ParseJson accepts. No BOP file comes close; deeper input would
// exhaust the stack of the code that walks the parsed value recursively (copies, dumps).
constexpr int kMaxJsonDepth = 64;

// Parses JSON text; `what` names the source in messages. Throws unseen::Error with nlohmann's
// message (which gives the byte position) for malformed JSON, and for nesting deeper than
// kMaxJsonDepth.
nlohmann::json ParseJson(std::string_view text, const std::string& what);

// Parses a JSON file (ParseJson). Throws unseen::Error naming the file for a missing or
// unreadable file, malformed JSON or nesting deeper than kMaxJsonDepth.
nlohmann::json ReadJsonFile(const std::string& path);

// Writes `json` to `path` (indented by `indent` spaces, -1 = compact). Throws on failure.
void WriteJsonFile(const std::string& path, const nlohmann::json& json, int indent = 1);
// The same keeping the insertion order of keys (frame ids in the order written).
void WriteJsonFile(const std::string& path, const nlohmann::ordered_json& json, int indent = 1);

// A BOP frame id key ("0", "17", ...) as an int. Throws naming `what` for anything else.
int ParseFrameId(const std::string& key, const std::string& what);

// `object[key]` as exactly `size` finite numbers. `what` describes where the object is
// (e.g. "scene_camera.json frame 3"). Throws naming what, key and the offending value.
std::vector<double> GetNumbers(const nlohmann::json& object, const std::string& key, size_t size,
                               const std::string& what);

// `object[key]` as a finite number; throws naming what and key when missing or not a number.
double GetNumber(const nlohmann::json& object, const std::string& key, const std::string& what);

// `object[key]` as an integer; throws naming what and key when missing or not an integer.
int GetInt(const nlohmann::json& object, const std::string& key, const std::string& what);

// The pose stored as a row-major rotation `object[rotation_key]` (9 numbers) and a
// translation `object[translation_key]` in millimetres, returned in metres. Throws naming
// `what` and the keys for a missing field, wrong length, NaN or a non-orthonormal rotation.
Rigid3d GetPoseMm(const nlohmann::json& object, const std::string& rotation_key,
                  const std::string& translation_key, const std::string& what);

// Sets object[rotation_key] (row-major, 9 numbers) and object[translation_key] (mm) from a
// pose in metres.
void SetPoseMm(const Rigid3d& pose, const std::string& rotation_key,
               const std::string& translation_key, nlohmann::json* object);

// BOP frame id formatting: 6 digits ("000042").
std::string FrameName(int frame_id);

}  // namespace unseen::bop
