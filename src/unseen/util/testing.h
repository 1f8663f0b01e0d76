// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Helpers shared by the unit tests (GoogleTest); not part of the library proper.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "unseen/util/error.h"

namespace unseen::testing {

// A fresh, empty directory for the running test: <temp>/unseen_<prefix>_<pid>_<suite>_<test>.
inline std::filesystem::path TestDir(const std::string& prefix) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      ("unseen_" + prefix + "_" + std::to_string(::getpid()) + "_" + info->test_suite_name() +
       "_" + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// Expects `fn()` to throw unseen::Error whose message contains every one of `substrings`.
template <typename Fn>
void ExpectError(Fn fn, const std::vector<std::string>& substrings) {
  try {
    fn();
    ADD_FAILURE() << "expected unseen::Error";
  } catch (const Error& e) {
    for (const std::string& s : substrings) EXPECT_THAT(e.what(), ::testing::HasSubstr(s));
  }
}

// The development sequences beside the repository (tests skip when absent).
inline std::string DevSequencesDir() {
  return std::string(UNSEEN_SOURCE_DIR) + "/../shared/data/sequences/";
}

}  // namespace unseen::testing
