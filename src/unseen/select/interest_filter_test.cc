// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/select/interest_filter.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "unseen/mesh/primitives.h"
#include "unseen/render/rasterizer.h"
#include "unseen/select/interest_filter_bank.h"
#include "unseen/track/test_scene.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

FilterFrame Frame(const cv::Mat& image) {
  FilterFrame f;
  f.image = image;
  f.camera = PinholeCamera::Centered(image.cols, image.rows, 200.0);
  return f;
}

cv::Mat Ones(const cv::Size& size) { return cv::Mat(size, CV_32FC1, cv::Scalar(1.0f)); }

// A textured background (fixed noise) with a 20x20 square of its own noise at `x`.
cv::Mat SceneWithSquareAt(int x) {
  cv::Mat image(96, 128, CV_32FC3);
  cv::RNG background(1);
  background.fill(image, cv::RNG::UNIFORM, 0.2, 0.5);
  cv::Mat square(20, 20, CV_32FC3);
  cv::RNG object(2);
  object.fill(square, cv::RNG::UNIFORM, 0.6, 1.0);
  square.copyTo(image(cv::Rect(x, 40, 20, 20)));
  return image;
}

TEST(ColourFilter, InterestNearTheReferenceColourOnly) {
  cv::Mat image(10, 20, CV_32FC3, cv::Scalar(0.1, 0.1, 0.9));       // red (BGR)
  image(cv::Rect(10, 0, 10, 10)).setTo(cv::Scalar(0.9, 0.1, 0.1));  // blue half
  ColourFilterOptions o;
  o.colours_bgr = {Eigen::Vector3f(0.1f, 0.15f, 0.85f)};
  o.radii = {0.3f};
  ColourFilter filter(o);
  cv::Mat interest = Ones(image.size());
  interest.at<float>(5, 2) = 0.0f;  // already of no interest: stays so (2.4)
  filter.Apply(Frame(image), &interest);
  EXPECT_NEAR(interest.at<float>(0, 0), 1.0f - 0.0050f / 0.09f, 1e-4);
  EXPECT_EQ(interest.at<float>(5, 2), 0.0f);
  EXPECT_EQ(interest.at<float>(0, 15), 0.0f);
  o.radii.clear();
  EXPECT_THROW(ColourFilter{o}, Error);
}

TEST(MotionFilter, MovingPixelsAfterTheBackgroundIsLearnt) {
  MotionFilter filter{MotionFilterOptions()};  // learns 8 frames
  cv::Mat interest;
  for (int i = 0; i < 8; ++i) {
    interest = Ones(cv::Size(128, 96));
    filter.Apply(Frame(SceneWithSquareAt(10)), &interest);
    EXPECT_EQ(cv::countNonZero(interest), 0) << "frame " << i;  // learning
  }
  EXPECT_TRUE(filter.ready());
  interest = Ones(cv::Size(128, 96));
  filter.Apply(Frame(SceneWithSquareAt(80)), &interest);
  // The square where it is now, and where it left the background bare, moved; the rest not.
  EXPECT_GT(cv::mean(interest(cv::Rect(83, 43, 14, 14)))[0], 0.9);
  EXPECT_EQ(cv::countNonZero(interest(cv::Rect(40, 0, 30, 96))), 0);
  EXPECT_EQ(cv::countNonZero(interest(cv::Rect(0, 0, 128, 30))), 0);
  // A frame of another size is an error.
  cv::Mat small = Ones(cv::Size(64, 48));
  EXPECT_THROW(filter.Apply(Frame(cv::Mat(48, 64, CV_32FC3, cv::Scalar(0.5, 0.5, 0.5))), &small),
               Error);
}

TEST(PositionFilter, PixelsWhosePointIsInTheBox) {
  FilterFrame frame = Frame(cv::Mat(40, 40, CV_32FC3, cv::Scalar(0.5, 0.5, 0.5)));
  frame.depth = cv::Mat(40, 40, CV_32FC1, cv::Scalar(2.0f));  // background at 2 m
  frame.depth(cv::Rect(10, 10, 10, 10)).setTo(0.8f);          // an object at 0.8 m
  frame.depth.at<float>(0, 0) = 0.0f;                         // no measurement
  PositionFilterOptions o;
  o.min_m = Eigen::Vector3d(-0.5, -0.5, 0.5);
  o.max_m = Eigen::Vector3d(0.5, 0.5, 1.0);
  PositionFilter filter(o);
  cv::Mat interest = Ones(frame.image.size());
  filter.Apply(frame, &interest);
  EXPECT_EQ(cv::countNonZero(interest), 100);
  EXPECT_EQ(cv::countNonZero(interest(cv::Rect(10, 10, 10, 10))), 100);
  frame.depth.release();
  EXPECT_THROW(filter.Apply(frame, &interest), Error);
  o.max_m.z() = 0.4;  // empty box
  EXPECT_THROW(PositionFilter{o}, Error);
}

// The square moves 3 px to the right a frame over the still background: interest on it
// for a filter looking rightwards, none for one looking leftwards, none on the background.
TEST(VelocityFilter, PixelsMovingAlongTheDirection) {
  VelocityFilterOptions right;
  VelocityFilterOptions left;
  left.direction = Eigen::Vector2d(-2.0, 0.0);  // any length
  VelocityFilter to_right(right), to_left(left);
  cv::Mat interest_right, interest_left;
  for (int i = 0; i < 3; ++i) {
    interest_right = Ones(cv::Size(128, 96));
    interest_left = Ones(cv::Size(128, 96));
    to_right.Apply(Frame(SceneWithSquareAt(40 + 3 * i)), &interest_right);
    to_left.Apply(Frame(SceneWithSquareAt(40 + 3 * i)), &interest_left);
    if (i == 0) {
      EXPECT_FALSE(to_right.ready());  // no motion from one frame
      EXPECT_EQ(cv::countNonZero(interest_right), 0);
    }
  }
  EXPECT_TRUE(to_right.ready());
  const cv::Rect on_square(49, 44, 12, 12);
  EXPECT_GT(cv::mean(interest_right(on_square))[0], 0.7);
  EXPECT_LT(cv::mean(interest_left(on_square))[0], 0.05);
  EXPECT_LT(cv::mean(interest_right(cv::Rect(0, 0, 128, 20)))[0], 0.05);  // 20 px away
  VelocityFilterOptions bad;
  bad.direction = Eigen::Vector2d::Zero();
  EXPECT_THROW(VelocityFilter{bad}, Error);
  bad = {};
  bad.max_angle_deg = 0.0;
  EXPECT_THROW(VelocityFilter{bad}, Error);
}

// The lettered cube turning and drifting over a textured background before a still
// camera: the pixels that move as its tracked poses say are the cube's, the still
// background is not; with the cube's depth the prediction is exact, without it (the
// origin's depth for every pixel) it is looser.
double MeanInterestOnAndOffTheCube(bool with_depth, double* off) {
  const Mesh cube = MakeLetteredCube(0.096, 64);
  const Rig rig = testing::OneCameraRig();
  const RigCamera& camera = rig.cameras[0];
  const cv::Mat background = testing::Background(camera.intrinsics, 5);
  auto pose = [](int t) {
    return Rigid3d(ExpSO3(Eigen::Vector3d(0.4 + 0.03 * t, 0.6, 0.1)),
                   Eigen::Vector3d(-0.05 + 0.006 * t, 0.01, 0.8));
  };
  TrackedMotionFilter filter{TrackedMotionFilterOptions()};
  cv::Mat interest;
  RenderBuffers render;
  cv::Mat on_cube;
  for (int t = 0; t < 3; ++t) {
    FilterFrame frame = Frame(testing::RenderOverBackground(cube, camera, pose(t), background));
    frame.camera = camera.intrinsics;
    Render(cube, camera.intrinsics, pose(t), camera.intrinsics.ImageRect(), RenderOptions{},
           &render);
    const cv::Rect roi(render.roi.x0, render.roi.y0, render.roi.width(), render.roi.height());
    on_cube = cv::Mat::zeros(frame.image.size(), CV_8UC1);
    render.mask.copyTo(on_cube(roi));
    if (with_depth) {
      frame.depth = cv::Mat::zeros(frame.image.size(), CV_32FC1);
      render.depth.copyTo(frame.depth(roi));
    }
    if (t > 0) {
      frame.world_from_obj = pose(t);
      frame.previous_world_from_obj = pose(t - 1);
    }
    interest = Ones(frame.image.size());
    filter.Apply(frame, &interest);
    if (t == 0) {
      EXPECT_EQ(cv::countNonZero(interest == 1.0f), interest.total());  // no judgement
    }
  }
  cv::Mat off_cube;
  cv::dilate(on_cube, off_cube, cv::Mat(), cv::Point(-1, -1), 16);
  off_cube = off_cube == 0;
  cv::erode(on_cube, on_cube, cv::Mat(), cv::Point(-1, -1), 4);  // off the outline
  *off = cv::mean(interest, off_cube)[0];
  return cv::mean(interest, on_cube)[0];
}

TEST(TrackedMotionFilter, PixelsMovingWithTheTrackedObject) {
  double off = 1.0;
  EXPECT_GT(MeanInterestOnAndOffTheCube(true, &off), 0.8);
  EXPECT_LT(off, 0.1);
  EXPECT_GT(MeanInterestOnAndOffTheCube(false, &off), 0.45);
  EXPECT_LT(off, 0.1);
  TrackedMotionFilterOptions bad;
  bad.max_difference_px = 0.0;
  EXPECT_THROW(TrackedMotionFilter{bad}, Error);
}

TEST(InterestFilterBank, ChainedFromItsFileAndErrorsNameTheFilter) {
  InterestFilterBank bank = ParseInterestFilterBank(R"(
filters:
  - type: motion
    warmup_frames: 10
  - type: colour
    colours_rgb: [[0.8, 0.8, 0.8]]
    radii: [0.5]
)",
                                                    "bank.yaml");
  ASSERT_EQ(bank.size(), 2);
  EXPECT_EQ(bank.filter(0).name(), "motion");
  EXPECT_EQ(bank.filter(1).name(), "colour");
  EXPECT_EQ(ParseInterestFilterBank(
                "filters:\n  - type: velocity\n    direction: [0, -1]\n    min_speed_px: 1\n",
                "bank.yaml")
                .filter(0)
                .name(),
            "velocity");
  EXPECT_EQ(ParseInterestFilterBank("filters: [{type: tracked_motion, max_difference_px: 2}]",
                                    "bank.yaml")
                .filter(0)
                .name(),
            "tracked_motion");
  for (int i = 0; i < 10; ++i) bank.Apply(Frame(SceneWithSquareAt(10)));
  EXPECT_TRUE(bank.ready());
  const cv::Mat interest = bank.Apply(Frame(SceneWithSquareAt(80)));
  // Moving and bright: the square; the bare background it left moved but is dark.
  EXPECT_GT(cv::mean(interest(cv::Rect(83, 43, 14, 14)))[0], 0.5);
  EXPECT_LT(cv::mean(interest(cv::Rect(13, 43, 14, 14)))[0], 0.1);

  struct Case {
    std::string text, message;
  };
  for (const Case& c : {
           Case{"filters:\n  - type: magic\n", "filters[0].type: 'magic'"},
           Case{"filters:\n  - type: motion\n    histroy: 5\n", "filters[0]"},
           Case{"filters:\n  - type: motion\n  - type: colour\n    colours_rgb: [[1, 0, 0]]\n",
                "filters[1]"},
           Case{"filters:\n  - type: position\n    min_m: [0, 0]\n    max_m: [1, 1, 1]\n",
                "[x, y, z]"},
           Case{"filters:\n  - type: velocity\n    direction: [1, 0, 0]\n", "[x, y]"},
           Case{"filters:\n  - type: velocity\n    max_angle_deg: 200\n", "max_angle_deg"},
           Case{"filter: []\n", "'filters' list"},
           Case{"filters: [\n", "malformed"},
       }) {
    try {
      ParseInterestFilterBank(c.text, "bank.yaml");
      ADD_FAILURE() << "no error for:\n" << c.text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bank.yaml"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace unseen
