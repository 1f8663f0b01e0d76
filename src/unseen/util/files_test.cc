// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/util/files.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

namespace unseen {
namespace {

namespace fs = std::filesystem;

TEST(Files, AnswersForFilesAndFolders) {
  const fs::path dir = fs::temp_directory_path() / "unseen_files_test";
  fs::create_directories(dir);
  const fs::path file = dir / "a.txt";
  std::ofstream(file) << "x";
  EXPECT_TRUE(IsFile(file));
  EXPECT_FALSE(IsFolder(file));
  EXPECT_TRUE(IsFolder(dir));
  EXPECT_FALSE(IsFile(dir));
  EXPECT_TRUE(Exists(file));
  EXPECT_FALSE(Exists(dir / "missing"));
  fs::remove_all(dir);
}

TEST(Files, PathsTheSystemRefusesAreNotThereInsteadOfThrowing) {
  // std::filesystem::is_regular_file(path) throws for these (ENAMETOOLONG, ENOTDIR).
  const fs::path too_long = fs::temp_directory_path() / std::string(5000, 'x');
  EXPECT_FALSE(IsFile(too_long));
  EXPECT_FALSE(IsFolder(too_long));
  EXPECT_FALSE(Exists(too_long));
  const fs::path file = fs::temp_directory_path() / "unseen_files_test_plain";
  std::ofstream(file) << "x";
  EXPECT_FALSE(IsFile(file / "below_a_file"));
  fs::remove(file);
}

}  // namespace
}  // namespace unseen
