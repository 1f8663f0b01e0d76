// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/util/memory.h"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>

namespace unseen {
namespace {

TEST(ResidentMemory, GrowsWhenMemoryIsTouched) {
  const int64_t before = ResidentMemoryBytes();
  ASSERT_GT(before, 0);
  constexpr size_t kBytes = 64 << 20;
  std::unique_ptr<char[]> block(new char[kBytes]);
  std::memset(block.get(), 1, kBytes);  // resident only once written
  const int64_t after = ResidentMemoryBytes();
  EXPECT_GT(after - before, int64_t(kBytes) * 9 / 10);
  EXPECT_EQ(block[kBytes - 1], 1);
}

}  // namespace
}  // namespace unseen
