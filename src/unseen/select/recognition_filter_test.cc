// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/select/recognition_filter.h"

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

const std::vector<cv::Scalar> kObjectPalette = {
    {0.1, 0.1, 0.85}, {0.1, 0.8, 0.9}, {0.6, 0.25, 0.1}, {0.2, 0.7, 0.2}, {0.95, 0.95, 0.95}};
const std::vector<cv::Scalar> kClutterPalette = {
    {0.5, 0.5, 0.5}, {0.2, 0.35, 0.5}, {0.8, 0.8, 0.3}, {0.6, 0.2, 0.6}, {0.1, 0.1, 0.85}};

cv::Mat Texture(uint64 seed) { return Blobs({160, 160}, kObjectPalette, 150, 3, 12, seed); }
cv::Mat Clutter(uint64 seed) { return Blobs({640, 480}, kClutterPalette, 500, 5, 25, seed); }

cv::Mat To8(const cv::Mat& image) {
  cv::Mat out;
  image.convertTo(out, CV_8UC3, 255.0);
  return out;
}

// Returns the same detections every time, counting the calls.
class FakeRecognizer : public ObjectRecognizer {
 public:
  FakeRecognizer(std::vector<Detection> detections, int* calls)
      : detections_(std::move(detections)), calls_(calls) {}
  std::string name() const override { return "fake"; }
  std::vector<Detection> Detect(const cv::Mat& bgr8) override {
    EXPECT_EQ(bgr8.type(), CV_8UC3);
    ++*calls_;
    return detections_;
  }

 private:
  std::vector<Detection> detections_;
  int* calls_;
};

TEST(RecognitionFilter, InterestInsideTheDetectionsOnly) {
  int calls = 0;
  // A box [10, 30) x [10, 20) scored 0.8 and a lower one overlapping it; a degenerate one.
  const std::vector<Detection> detections = {
      {{{10, 10}, {30, 10}, {30, 20}, {10, 20}}, 0.8},
      {{{25, 15}, {40, 15}, {40, 30}, {25, 30}}, 0.5},
      {{{0, 0}, {5, 5}}, 1.0},
  };
  RecognitionFilter filter(std::make_unique<FakeRecognizer>(detections, &calls));
  EXPECT_EQ(filter.name(), "recognition");
  cv::Mat interest(48, 64, CV_32FC1, cv::Scalar(1.0f));
  interest.at<float>(12, 12) = 0.0f;  // of no interest already: stays so
  filter.Apply(FilterFrameOf(cv::Mat(48, 64, CV_32FC3, cv::Scalar(0.5, 0.5, 0.5))), &interest);
  EXPECT_EQ(calls, 1);
  EXPECT_FLOAT_EQ(interest.at<float>(15, 20), 0.8f);
  EXPECT_FLOAT_EQ(interest.at<float>(17, 28), 0.8f);  // in both: the higher score
  EXPECT_FLOAT_EQ(interest.at<float>(25, 35), 0.5f);
  EXPECT_EQ(interest.at<float>(12, 12), 0.0f);
  EXPECT_EQ(interest.at<float>(2, 2), 0.0f);
  EXPECT_EQ(interest.at<float>(40, 50), 0.0f);
  EXPECT_EQ(cv::countNonZero(interest(cv::Rect(0, 32, 64, 16))), 0);  // below both boxes
  EXPECT_EQ(cv::countNonZero(interest(cv::Rect(42, 0, 22, 48))), 0);  // right of both
  EXPECT_EQ(cv::countNonZero(interest(cv::Rect(0, 0, 8, 48))), 0);    // left of both
  // Nothing left to judge: the recogniser is not run.
  cv::Mat none(48, 64, CV_32FC1, cv::Scalar(0.0f));
  filter.Apply(FilterFrameOf(cv::Mat(48, 64, CV_32FC3, cv::Scalar(0.5, 0.5, 0.5))), &none);
  EXPECT_EQ(calls, 1);
  EXPECT_THROW(RecognitionFilter{nullptr}, Error);
}

TEST(FeatureRecognizer, FindsTheTexturedObjectRotatedAndScaled) {
  FeatureRecognizer recognizer{FeatureRecognizerOptions()};
  recognizer.AddReference(Texture(11), cv::Rect());
  recognizer.AddReference(Texture(12), cv::Rect());  // another object, not in the scene
  EXPECT_EQ(recognizer.num_references(), 2);
  cv::Mat scene = Clutter(3);
  const cv::Matx33d scene_from_object = Similarity(15.0, 1.2, 300.0, 120.0);
  Paste(Texture(11), scene_from_object, &scene);
  const std::vector<Detection> found = recognizer.Detect(To8(scene));
  ASSERT_EQ(found.size(), 1u);
  EXPECT_GT(found[0].score, 0.5);
  EXPECT_LE(found[0].score, 1.0);
  const std::vector<cv::Point2f> corners = {{0, 0}, {160, 0}, {160, 160}, {0, 160}};
  ASSERT_EQ(found[0].polygon.size(), corners.size());
  for (size_t i = 0; i < corners.size(); ++i) {
    const cv::Vec3d p = scene_from_object * cv::Vec3d(corners[i].x, corners[i].y, 1.0);
    EXPECT_LT(cv::norm(found[0].polygon[i] - cv::Point2f(p[0] / p[2], p[1] / p[2])), 3.0)
        << "corner " << i << " at " << found[0].polygon[i];
  }
  // The clutter alone, and the object's own texture upside-down-mirrored (a homography
  // that flips the outline), give nothing.
  EXPECT_TRUE(recognizer.Detect(To8(Clutter(4))).empty());
  cv::Mat mirrored = Clutter(5), flipped;
  cv::flip(Texture(11), flipped, 1);
  Paste(flipped, Similarity(0.0, 1.0, 200.0, 150.0), &mirrored);
  EXPECT_TRUE(recognizer.Detect(To8(mirrored)).empty());

  // Through the filter: interest on the object only.
  RecognitionFilter filter(std::make_unique<FeatureRecognizer>(std::move(recognizer)));
  cv::Mat interest(scene.size(), CV_32FC1, cv::Scalar(1.0f));
  filter.Apply(FilterFrameOf(scene), &interest);
  const cv::Vec3d centre = scene_from_object * cv::Vec3d(80.0, 80.0, 1.0);
  EXPECT_GT(interest.at<float>(static_cast<int>(centre[1]), static_cast<int>(centre[0])), 0.5f);
  EXPECT_EQ(interest.at<float>(450, 20), 0.0f);
}

TEST(FeatureRecognizer, RejectsBadReferencesAndOptions) {
  FeatureRecognizer recognizer{FeatureRecognizerOptions()};
  EXPECT_TRUE(recognizer.Detect(To8(Clutter(4))).empty());  // no reference yet
  const cv::Mat flat(100, 100, CV_32FC3, cv::Scalar(0.5, 0.5, 0.5));
  try {
    recognizer.AddReference(flat, cv::Rect(), "flat.png");
    ADD_FAILURE() << "no error for a reference without texture";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("flat.png: 0 ORB keypoints"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(recognizer.AddReference(Texture(11), cv::Rect(100, 100, 100, 100)), Error);
  FeatureRecognizerOptions o;
  o.min_inliers = 3;
  EXPECT_THROW(o.Check(), Error);
  o = {};
  o.ratio = 1.5;
  EXPECT_THROW(o.Check(), Error);
  o = {};
  o.max_area_fraction = 0.0;
  EXPECT_THROW(FeatureRecognizer{o}, Error);
}

TEST(RecognitionFilter, FromTheYamlBankWithPathsBesideTheFile) {
  const fs::path folder =
      fs::temp_directory_path() / ("unseen_recognition_test_" + std::to_string(::getpid()));
  fs::create_directories(folder / "refs");
  ASSERT_TRUE(cv::imwrite((folder / "refs/front.png").string(), To8(Texture(11))));
  const std::string bank_path = (folder / "bank.yaml").string();
  std::ofstream(bank_path) << "filters:\n  - type: recognition\n"
                              "    reference_images: [refs/front.png]\n"
                              "    reference_rects: [[0, 0, 160, 160]]\n"
                              "    min_inliers: 15\n";
  InterestFilterBank bank = LoadInterestFilterBank(bank_path);
  ASSERT_EQ(bank.size(), 1);
  EXPECT_EQ(bank.filter(0).name(), "recognition");
  cv::Mat scene = Clutter(3);
  Paste(Texture(11), Similarity(-10.0, 0.9, 250.0, 200.0), &scene);
  const cv::Mat interest = bank.Apply(FilterFrameOf(scene));
  EXPECT_GT(interest.at<float>(270, 320), 0.5f);
  EXPECT_EQ(interest.at<float>(20, 20), 0.0f);

  struct Case {
    std::string entry, message;
  };
  for (const Case& c : {
           Case{"reference_images: [refs/front.png, refs/missing.png]",
                "filters[0].reference_images[1]: image file '"},
           Case{"reference_images: [refs/missing.png]", "refs/missing.png' not found"},
           Case{"reference_images: []", "needs reference_images"},
           Case{"reference_images: refs/front.png", "has the wrong type"},
           Case{"reference_images: [refs/front.png]\n    reference_rects: [[0, 0, 10]]",
                "reference_rects[0]: [0, 0, 10] must be [x, y, width, height]"},
           Case{"reference_images: [refs/front.png]\n    reference_rects: [[100, 0, 100, 50]]",
                "rectangle [100, 0, 100, 50] is not inside the 160x160 image"},
           Case{"reference_images: [refs/front.png]\n    reference_rects: [[0, 0, 9, 9], [1, 1, 2, "
                "2]]",
                "2 rectangles for 1 reference_images"},
           Case{"reference_images: [refs/front.png]\n    min_inliers: 2", "min_inliers 2"},
       }) {
    const std::string text = "filters:\n  - type: recognition\n    " + c.entry + "\n";
    try {
      ParseInterestFilterBank(text, "bank.yaml", folder.string());
      ADD_FAILURE() << "no error for:\n" << text;
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(c.message), std::string::npos) << message;
      EXPECT_NE(message.find("bank.yaml: filters[0]"), std::string::npos) << message;
    }
  }
  fs::remove_all(folder);
}

// The cube of a rendered sequence, from a photo of it in the first frame (its visible
// mask's box), found a second later within a few pixels of its box.
TEST(FeatureRecognizer, FindsTheCubeOfARealSequence) {
  cv::Mat first, first_mask, later, mask;
  if (!testing::ReadCubeClutterFrame(0, &first, &first_mask) ||
      !testing::ReadCubeClutterFrame(30, &later, &mask)) {
    GTEST_SKIP() << "../shared/data/sequences/cube_clutter_sidelight is absent";
  }
  FeatureRecognizer recognizer{FeatureRecognizerOptions()};
  recognizer.AddReference(first, cv::boundingRect(first_mask));
  const std::vector<Detection> found = recognizer.Detect(later);
  ASSERT_EQ(found.size(), 1u);
  const cv::Rect truth = cv::boundingRect(mask);
  const cv::Rect box = cv::boundingRect(found[0].polygon);
  EXPECT_GT(static_cast<double>((box & truth).area()) / (box | truth).area(), 0.8)
      << "found " << box << ", truth " << truth;
}

}  // namespace
}  // namespace unseen
