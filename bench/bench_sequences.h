// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The sequences a benchmark runs on: a folder of sequences (or one sequence) and a
// comma-separated list of more such folders.
#pragma once

#include <algorithm>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "unseen/util/logging.h"

namespace unseen::bench {

// A sequence folder: sequence.json, or a plain BOP scene's scene_camera.json.
inline bool IsSequence(const std::filesystem::path& p) {
  return std::filesystem::exists(p / "sequence.json") ||
         std::filesystem::exists(p / "scene_camera.json");
}

// `dir` itself when it is a sequence, else the sequences directly in it, sorted.
inline std::vector<std::filesystem::path> SequencesIn(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> out;
  if (!std::filesystem::is_directory(dir)) return out;
  if (IsSequence(dir)) return {dir};
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.is_directory() && IsSequence(entry.path())) out.push_back(entry.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The sequences of `data_dir` (a warning when it has none), then those of each folder in
// `extra` (comma-separated).
inline std::vector<std::filesystem::path> BenchmarkSequences(const std::string& data_dir,
                                                             const std::string& extra) {
  std::vector<std::filesystem::path> paths = SequencesIn(data_dir);
  if (paths.empty()) UNSEEN_LOG_WARN("{}: no sequences found", data_dir);
  std::stringstream folders(extra);
  for (std::string dir; std::getline(folders, dir, ',');) {
    for (const std::filesystem::path& p : SequencesIn(dir)) paths.push_back(p);
  }
  return paths;
}

}  // namespace unseen::bench
