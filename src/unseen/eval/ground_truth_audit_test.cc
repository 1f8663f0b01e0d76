// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/eval/ground_truth_audit.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "unseen/eval/test_sequence.h"
#include "unseen/util/testing.h"

namespace unseen {
namespace {

TEST(GroundTruthAudit, TrustsGroundTruthOnTheMeasuredSurfaceOnly) {
  const std::string dir = testing::WriteRgbdTestSequence((std::filesystem::temp_directory_path() / "unseen_gt_audit_test").string(), 5, 3);
  const Sequence sequence = Sequence::Open(dir);
  const GroundTruthAudit audit = AuditGroundTruthWithDepth(sequence, sequence.LoadModel());
  ASSERT_EQ(audit.frames.size(), 5u);
  EXPECT_EQ(audit.judged, 5);
  EXPECT_EQ(audit.trusted, 3);
  for (int i = 0; i < 3; ++i) {
    EXPECT_GT(audit.agreement[i], 0.95) << i;
    EXPECT_TRUE(audit.Trusted(i));
  }
  for (int i = 3; i < 5; ++i) {
    EXPECT_LT(audit.agreement[i], 0.2) << i;  // 3 cm behind the surface it claims
    EXPECT_FALSE(audit.Trusted(i));
  }
  EXPECT_NE(audit.Summary().find("3 trusted"), std::string::npos) << audit.Summary();
  // A looser distance trusts them too.
  GroundTruthAuditOptions loose;
  loose.agree_distance_m = 0.05;
  EXPECT_EQ(AuditGroundTruthWithDepth(sequence, sequence.LoadModel(), loose).trusted, 5);
  std::filesystem::remove_all(dir);
}

TEST(GroundTruthAudit, RefusesASequenceWithoutDepth) {
  const std::string dir =
      (std::filesystem::temp_directory_path() / "unseen_gt_audit_no_depth").string();
  testing::WriteTestSequence(dir, 2);
  const Sequence sequence = Sequence::Open(dir);
  testing::ExpectError([&] { AuditGroundTruthWithDepth(sequence, sequence.LoadModel()); },
                         {"no depth"});
  GroundTruthAuditOptions bad;
  bad.min_agreement = 1.5;
  testing::ExpectError([&] { bad.Check(); }, {"min_agreement"});
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace unseen
