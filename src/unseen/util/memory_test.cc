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

// AddressSanitizer brings an allocator of its own, which glibc's settings do not reach.
#if defined(__SANITIZE_ADDRESS__)
#define UNSEEN_TEST_OWN_ALLOCATOR 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define UNSEEN_TEST_OWN_ALLOCATOR 1
#endif
#endif

TEST(ResidentMemory, FreedBlocksStayForReuse) {
#if defined(UNSEEN_TEST_OWN_ALLOCATOR)
  GTEST_SKIP() << "the sanitizer's allocator replaces glibc's";
#elif defined(__GLIBC__)
  ASSERT_TRUE(KeepFreedMemoryForReuse());
  // A block of a frame's size, written and freed, stays resident for the next one instead
  // of going back to the system (by default glibc maps a block this large on its own and
  // unmaps it when freed).
  constexpr size_t kBytes = 24 << 20;
  const int64_t before = ResidentMemoryBytes();
  {
    std::unique_ptr<char[]> block(new char[kBytes]);
    std::memset(block.get(), 1, kBytes);
    asm volatile("" : : "r"(block.get()) : "memory");  // the writes are not optimised away
    EXPECT_EQ(block[kBytes / 2], 1);
  }
  const int64_t after_free = ResidentMemoryBytes();
  EXPECT_GT(after_free - before, int64_t(kBytes) * 9 / 10);
  // The next block of that size takes the same memory: nothing more becomes resident.
  {
    std::unique_ptr<char[]> block(new char[kBytes]);
    std::memset(block.get(), 2, kBytes);
    asm volatile("" : : "r"(block.get()) : "memory");
    EXPECT_EQ(block[kBytes / 2], 2);
  }
  EXPECT_LT(ResidentMemoryBytes() - after_free, int64_t(kBytes) / 10);
#else
  EXPECT_FALSE(KeepFreedMemoryForReuse());
#endif
}

}  // namespace
}  // namespace unseen
