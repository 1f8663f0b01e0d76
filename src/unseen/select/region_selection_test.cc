// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/select/region_selection.h"

#include <gtest/gtest.h>

#include "unseen/util/error.h"

namespace unseen {
namespace {

class Selection : public ::testing::Test {
 protected:
  void SetUp() override {
    labels_ = cv::Mat(100, 200, CV_32SC1, cv::Scalar(0));
    interest_ = cv::Mat(100, 200, CV_32FC1, cv::Scalar(0.0f));
    depth_ = cv::Mat(100, 200, CV_32FC1, cv::Scalar(2.0f));
    // Region 1: 40x40 px, interest 0.6 on all of it, at 1 m (40 px at f 400: 0.1 m).
    Paint(1, cv::Rect(10, 10, 40, 40), 0.6f, 1.0f);
    // Region 2: 30x30 px, interest 0.9 on all of it, at 1 m: the highest mean interest.
    Paint(2, cv::Rect(100, 10, 30, 30), 0.9f, 1.0f);
    // Region 3: 40x40 px with interest on a tenth only.
    Paint(3, cv::Rect(150, 50, 40, 40), 0.0f, 1.0f);
    interest_(cv::Rect(150, 50, 40, 4)).setTo(1.0f);
  }
  void Paint(int label, const cv::Rect& r, float interest, float depth) {
    labels_(r).setTo(label);
    interest_(r).setTo(interest);
    depth_(r).setTo(depth);
  }
  cv::Mat labels_, interest_, depth_;
  const PinholeCamera camera_ = PinholeCamera::Centered(200, 100, 400.0);
  RegionSelectionOptions options_;
};

TEST_F(Selection, TheCandidateOfHighestMeanInterest) {
  const RegionSelection s = SelectRegion(labels_, interest_, cv::Mat(), depth_, camera_, options_);
  ASSERT_EQ(s.regions.size(), 3u);
  ASSERT_TRUE(s.found());
  EXPECT_EQ(s.object().label, 2);
  const RegionCandidate& r1 = s.regions[0];
  EXPECT_TRUE(r1.candidate);
  EXPECT_EQ(r1.total_area, 1600);
  EXPECT_EQ(r1.interest_area, 1600);
  EXPECT_NEAR(r1.mean_interest, 0.6, 1e-6);
  EXPECT_NEAR(r1.mean_depth_m, 1.0, 1e-6);
  EXPECT_NEAR(r1.width_m, 0.1, 1e-6);
  EXPECT_EQ(r1.box.x0, 10);
  EXPECT_EQ(r1.box.x1, 50);
  EXPECT_FALSE(s.regions[2].candidate);  // a tenth of it of interest
  EXPECT_NE(s.regions[2].rejected.find("share"), std::string::npos) << s.regions[2].rejected;
}

TEST_F(Selection, SizeAreaAndNoCandidateIsAStatus) {
  options_.max_size_m = 0.09;  // region 1 (0.1 m) too large; region 2 is 0.075 m
  RegionSelection s = SelectRegion(labels_, interest_, cv::Mat(), depth_, camera_, options_);
  EXPECT_FALSE(s.regions[0].candidate);
  EXPECT_NE(s.regions[0].rejected.find("size"), std::string::npos);
  EXPECT_EQ(s.object().label, 2);
  options_.min_area_px = 2000;  // none is large enough
  s = SelectRegion(labels_, interest_, cv::Mat(), depth_, camera_, options_);
  EXPECT_FALSE(s.found());
  // Without texture, depth does not count: no size, so no candidate with a depth map.
  options_ = RegionSelectionOptions();
  options_.min_texturedness = 0.5;
  const cv::Mat flat(labels_.size(), CV_32FC1, cv::Scalar(0.0f));
  s = SelectRegion(labels_, interest_, flat, depth_, camera_, options_);
  EXPECT_FALSE(s.found());
  EXPECT_NE(s.regions[1].rejected.find("no depth"), std::string::npos);
  // Without any depth map, no size test.
  s = SelectRegion(labels_, interest_, cv::Mat(), cv::Mat(), camera_, options_);
  EXPECT_EQ(s.object().label, 2);
  EXPECT_THROW(SelectRegion(labels_, interest_(cv::Rect(0, 0, 10, 10)), cv::Mat(), cv::Mat(),
                            camera_, options_),
               Error);
  options_.max_size_m = -1.0;
  EXPECT_THROW(options_.Check(), Error);
}

TEST(InterestRegions, ConnectedPartsOfTheInterestMap) {
  cv::Mat interest(50, 50, CV_32FC1, cv::Scalar(0.0f));
  interest(cv::Rect(5, 5, 10, 10)).setTo(1.0f);
  interest(cv::Rect(16, 5, 10, 10)).setTo(1.0f);  // 1 px apart: joined by the closing
  interest(cv::Rect(35, 35, 10, 10)).setTo(0.8f);
  const cv::Mat labels = InterestRegions(interest, 0.5, 5);
  double max_label = 0;
  cv::minMaxLoc(labels, nullptr, &max_label);
  EXPECT_EQ(max_label, 2);
  EXPECT_EQ(labels.at<int>(10, 10), labels.at<int>(10, 20));
  EXPECT_NE(labels.at<int>(10, 10), labels.at<int>(40, 40));
  EXPECT_EQ(labels.at<int>(0, 0), 0);
}

}  // namespace
}  // namespace unseen
