// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/util/progress.h"

#include <gtest/gtest.h>

#include "unseen/util/error.h"

namespace unseen {
namespace {

TEST(ProgressLine, FormatsRateAndEta) {
  EXPECT_EQ(ProgressLine::Format("track", 10, 30, 2.0), "track 10/30 frames, 5.0 fps, ETA 4 s");
  EXPECT_EQ(ProgressLine::Format("track", 30, 30, 3.0), "track 30/30 frames, 10.0 fps");
  EXPECT_EQ(ProgressLine::Format("x", 0, 5, 0.0), "x 0/5 frames, 0.0 fps");
}

TEST(Error, CheckMacroThrowsWithMessage) {
  EXPECT_NO_THROW(UNSEEN_CHECK(1 + 1 == 2, "never"));
  try {
    UNSEEN_CHECK(false, "{}: field '{}' has value {}", "a.json", "fps", -3);
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "a.json: field 'fps' has value -3");
  }
}

}  // namespace
}  // namespace unseen
