// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/select/cooccurrence_filter.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "unseen/select/interest_filter_bank.h"
#include "unseen/select/test_images.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;
using testing::Blobs;
using testing::FilterFrameOf;
using testing::Paste;
using testing::Similarity;
using testing::TempFolder;

// BGR in [0, 1].
const std::vector<cv::Scalar> kObjectPalette = {
    {0.1, 0.1, 0.85}, {0.1, 0.8, 0.9}, {0.6, 0.25, 0.1}, {0.2, 0.7, 0.2}};
// Shares the object's red, in another arrangement.
const std::vector<cv::Scalar> kClutterPalette = {{0.5, 0.5, 0.5},  {0.2, 0.35, 0.5},
                                                 {0.8, 0.8, 0.3},  {0.6, 0.2, 0.6},
                                                 {0.1, 0.1, 0.85}, {0.9, 0.9, 0.9}};

struct Scenes {
  cv::Mat reference, reference_mask, moved, moved_mask;
};

// The object (80x80 blobs) upright at (200, 150) in the reference scene; rotated by 10 deg,
// 10 % larger at about (420, 260) over other clutter in the moved one.
Scenes MakeScenes() {
  const cv::Mat object = Blobs({80, 80}, kObjectPalette, 60, 3, 8, 7);
  Scenes s;
  s.reference = Blobs({640, 480}, kClutterPalette, 500, 5, 25, 1);
  s.reference_mask = Paste(object, Similarity(0.0, 1.0, 200.0, 150.0), &s.reference);
  s.moved = Blobs({640, 480}, kClutterPalette, 500, 5, 25, 2);
  s.moved_mask = Paste(object, Similarity(10.0, 1.1, 420.0, 250.0), &s.moved);
  return s;
}

double MeanWhere(const cv::Mat& interest, const cv::Mat& mask) {
  return cv::mean(interest, mask)[0];
}

TEST(CooccurrenceFilter, InterestOnTheObjectNotOnTheClutter) {
  const Scenes s = MakeScenes();
  CooccurrenceFilterOptions o;
  o.scales = {0.9, 1.0, 1.15};
  CooccurrenceFilter filter(o);
  EXPECT_FALSE(filter.ready());
  filter.Learn(s.reference, cv::Rect(200, 150, 80, 80));
  ASSERT_TRUE(filter.ready());
  EXPECT_EQ(filter.window_size(), cv::Size(80, 80));
  for (const auto& [image, mask] :
       {std::pair(s.reference, s.reference_mask), std::pair(s.moved, s.moved_mask)}) {
    cv::Mat interest(image.size(), CV_32FC1, cv::Scalar(1.0f));
    filter.Apply(FilterFrameOf(image), &interest);
    const double inside = MeanWhere(interest, mask), outside = MeanWhere(interest, mask == 0);
    EXPECT_GT(inside, 0.5);
    EXPECT_GT(inside, 3.0 * outside) << "inside " << inside << ", outside " << outside;
    double lo = 0.0, hi = 0.0;
    cv::minMaxLoc(interest, &lo, &hi);
    EXPECT_GE(lo, 0.0);
    EXPECT_LE(hi, 1.0);
  }
}

// Clutter of two of the object's own colours, in other proportions (red with yellow
// specks): every pixel has an object colour, the histograms still differ.
TEST(CooccurrenceFilter, TellsTheProportionsOfTheSameColours) {
  const cv::Mat object = Blobs({80, 80}, kObjectPalette, 60, 3, 8, 7);
  cv::Mat scene = Blobs({640, 480}, {kObjectPalette[0], kObjectPalette[1]}, 800, 1, 3, 3);
  const cv::Mat mask = Paste(object, Similarity(-8.0, 1.0, 300.0, 200.0), &scene);
  CooccurrenceFilter filter(CooccurrenceFilterOptions{});
  filter.Learn(object, cv::Rect(0, 0, 80, 80));
  cv::Mat interest(scene.size(), CV_32FC1, cv::Scalar(1.0f));
  filter.Apply(FilterFrameOf(scene), &interest);
  const double inside = MeanWhere(interest, mask), outside = MeanWhere(interest, mask == 0);
  EXPECT_GT(inside, 0.5);
  EXPECT_GT(inside, 3.0 * outside) << "inside " << inside << ", outside " << outside;
}

// A filter multiplies (2.4): pixels already at zero stay there, windows centred on them are
// not scored; a filter learnt from another object finds nothing.
TEST(CooccurrenceFilter, MultipliesAndLearnsFromAMask) {
  const Scenes s = MakeScenes();
  CooccurrenceFilter object(CooccurrenceFilterOptions{});
  object.Learn(s.reference, s.reference_mask);
  cv::Mat interest(s.moved.size(), CV_32FC1, cv::Scalar(0.5f));
  interest(cv::Rect(0, 0, 640, 240)).setTo(0.0f);  // the top half: of no interest already
  object.Apply(FilterFrameOf(s.moved), &interest);
  EXPECT_EQ(cv::countNonZero(interest(cv::Rect(0, 0, 640, 240))), 0);
  EXPECT_GT(MeanWhere(interest, s.moved_mask), 0.25);  // the object is in the bottom half
  EXPECT_LE(MeanWhere(interest, s.moved_mask), 0.5);

  // An object of other colours is not in the scene: no interest anywhere.
  const std::vector<cv::Scalar> other_palette = {{0.9, 0.5, 0.9}, {0.0, 0.0, 0.0}, {0.9, 0.9, 0.1}};
  CooccurrenceFilter other(CooccurrenceFilterOptions{});
  other.Learn(Blobs({80, 80}, other_palette, 60, 3, 8, 9), cv::Rect(0, 0, 80, 80));
  cv::Mat ones(s.moved.size(), CV_32FC1, cv::Scalar(1.0f));
  other.Apply(FilterFrameOf(s.moved), &ones);
  EXPECT_LT(cv::mean(ones)[0], 0.02);

  // Before learning, and on an image smaller than a window: no interest, no error.
  CooccurrenceFilter unlearnt(CooccurrenceFilterOptions{});
  cv::Mat small(8, 8, CV_32FC1, cv::Scalar(1.0f));
  unlearnt.Apply(FilterFrameOf(cv::Mat(8, 8, CV_32FC3, cv::Scalar(0.1, 0.1, 0.85))), &small);
  EXPECT_EQ(cv::countNonZero(small), 0);
  small.setTo(1.0f);
  object.Apply(FilterFrameOf(cv::Mat(8, 8, CV_32FC3, cv::Scalar(0.1, 0.1, 0.85))), &small);
  EXPECT_EQ(cv::countNonZero(small), 0);
  EXPECT_THROW(object.Learn(s.reference, cv::Mat(s.reference.size(), CV_8UC1, cv::Scalar(0))),
               Error);
  EXPECT_THROW(object.Learn(s.reference, cv::Rect(600, 400, 80, 80)), Error);
}

TEST(CooccurrenceFilterOptions, CheckRejectsNonsense) {
  EXPECT_NO_THROW(CooccurrenceFilterOptions().Check());
  auto rejects = [](auto&& edit) {
    CooccurrenceFilterOptions o;
    edit(o);
    EXPECT_THROW(o.Check(), Error);
  };
  rejects([](CooccurrenceFilterOptions& o) { o.colours = 1; });
  rejects([](CooccurrenceFilterOptions& o) { o.distance_edges_px = {3.0, 2.0}; });
  rejects([](CooccurrenceFilterOptions& o) { o.distance_edges_px = {4.0}; });
  rejects([](CooccurrenceFilterOptions& o) { o.stride_px = 0; });
  rejects([](CooccurrenceFilterOptions& o) { o.scales = {}; });
  rejects([](CooccurrenceFilterOptions& o) { o.min_score = 0.7; });
  rejects([](CooccurrenceFilterOptions& o) {
    o.reference_image = "x.png";
    o.reference_rect = cv::Rect(0, 0, -5, 10);
  });
}

TEST(CooccurrenceFilter, FromTheYamlBankWithPathsBesideTheFile) {
  const Scenes s = MakeScenes();
  TempFolder folder("unseen_cooccurrence_test");
  cv::Mat reference8;
  s.reference.convertTo(reference8, CV_8UC3, 255.0);
  ASSERT_TRUE(cv::imwrite((folder.path() / "object.png").string(), reference8));
  const std::string bank_path = (folder.path() / "bank.yaml").string();
  std::ofstream(bank_path) << "filters:\n  - type: cooccurrence\n"
                              "    reference_image: object.png\n"
                              "    reference_rect: [200, 150, 80, 80]\n"
                              "    colours: 10\n    scales: [1.0]\n";
  InterestFilterBank bank = LoadInterestFilterBank(bank_path);
  ASSERT_EQ(bank.size(), 1);
  EXPECT_EQ(bank.filter(0).name(), "cooccurrence");
  const cv::Mat interest = bank.Apply(FilterFrameOf(s.moved));
  EXPECT_GT(MeanWhere(interest, s.moved_mask), 3.0 * MeanWhere(interest, s.moved_mask == 0));

  struct Case {
    std::string entry, message;
  };
  for (const Case& c : {
           Case{"reference_image: missing.png", "missing.png' not found"},
           Case{"reference_image: object.png\n    reference_rect: [1, 2, 3]", "[1, 2, 3]"},
           Case{"reference_image: object.png\n    reference_rect: [600, 400, 80, 80]",
                "reference_rect [600, 400, 80, 80] is not inside the 640x480"},
           Case{"reference_image: object.png\n    reference_rect: [0, 0, -4, 8]",
                "reference_rect [0, 0, -4, 8]"},
           Case{"reference_image: object.png\n    min_score: 2", "min_score 2"},
           Case{"reference_rect: [0, 0, 4, 8]", "needs a reference_image"},
           Case{"reference_image: object.png\n    colour: 4", "unknown key 'colour'"},
       }) {
    const std::string text = "filters:\n  - type: cooccurrence\n    " + c.entry + "\n";
    try {
      ParseInterestFilterBank(text, "bank.yaml", folder.path().string());
      ADD_FAILURE() << "no error for:\n" << text;
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(c.message), std::string::npos) << message;
      EXPECT_NE(message.find("bank.yaml: filters[0]"), std::string::npos) << message;
    }
  }
}

// The real cube of a rendered sequence, learnt from its first frame's visible mask: the
// interest on it a second later is well above that on the coffee-photo background.
TEST(CooccurrenceFilter, FindsTheCubeOfARealSequence) {
  cv::Mat first, first_mask, later, mask;
  if (!testing::ReadCubeClutterFrame(0, &first, &first_mask) ||
      !testing::ReadCubeClutterFrame(30, &later, &mask)) {
    GTEST_SKIP() << "../shared/data/sequences/cube_clutter_sidelight is absent";
  }
  CooccurrenceFilter filter(CooccurrenceFilterOptions{});
  filter.Learn(first, first_mask);
  cv::Mat image;
  later.convertTo(image, CV_32FC3, 1.0 / 255.0);
  cv::Mat interest(image.size(), CV_32FC1, cv::Scalar(1.0f));
  filter.Apply(FilterFrameOf(image), &interest);
  EXPECT_GT(MeanWhere(interest, mask), 0.8);
  EXPECT_GT(MeanWhere(interest, mask), 2.0 * MeanWhere(interest, mask == 0));
}

}  // namespace
}  // namespace unseen
