// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// File-system queries that never throw. std::filesystem's own throw filesystem_error for a
// path the system refuses to look at (a name too long, a component that is not a folder,
// no permission); for a reader of outside input that is just "not there", which it reports
// as unseen::Error naming the file and field.
#pragma once

#include <filesystem>
#include <system_error>

namespace unseen {

// `path` exists and is a regular file (or a link to one).
inline bool IsFile(const std::filesystem::path& path) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}

// `path` exists and is a folder (or a link to one).
inline bool IsFolder(const std::filesystem::path& path) {
  std::error_code ec;
  return std::filesystem::is_directory(path, ec);
}

// Something exists at `path`.
inline bool Exists(const std::filesystem::path& path) {
  std::error_code ec;
  return std::filesystem::exists(path, ec);
}

}  // namespace unseen
