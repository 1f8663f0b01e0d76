// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Test support (header only, for the CLI tests): run the built `unseen` binary (UNSEEN_CLI,
// defined by the test target) and read what it printed.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <fmt/format.h>

namespace unseen::testing {

// A path in the temporary folder, unique to the test program through `prefix` and to its
// process (two test runs at once, from two checkouts, do not share files).
inline std::string CliTempPath(const std::string& prefix, const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          fmt::format("unseen_{}_{}_{}", prefix, static_cast<long>(::getpid()), name))
      .string();
}

inline std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct CliResult {
  int exit_code = -1;
  std::string out, err;
};

// Runs `unseen <args>`, capturing stdout and stderr in files named after `prefix`.
inline CliResult RunCli(const std::string& prefix, const std::string& args) {
  const std::string out = CliTempPath(prefix, "stdout.txt");
  const std::string err = CliTempPath(prefix, "stderr.txt");
  const std::string command = fmt::format("'{}' {} > '{}' 2> '{}'", UNSEEN_CLI, args, out, err);
  const int status = std::system(command.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadText(out);
  r.err = ReadText(err);
  return r;
}

}  // namespace unseen::testing
