// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/virtual_image.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>

#include "unseen/image/filters.h"

namespace unseen {
namespace {

// TransferShading as written down (PreprocessOptions::shading_transfer): the input and the
// composite over the fully covered pixels (weight 1, else 0) low-passed as whole images,
// their ratio where there is support, applied to every covered pixel.
cv::Mat ReferenceShading(const cv::Mat& input, const VirtualImage& w, double sigma_px) {
  cv::Mat real(w.composite.size(), CV_32FC4, cv::Scalar::all(0.0));
  cv::Mat model(w.composite.size(), CV_32FC3, cv::Scalar::all(0.0));
  for (int y = 0; y < real.rows; ++y) {
    for (int x = 0; x < real.cols; ++x) {
      if (w.coverage.at<uint8_t>(y, x) != 4) continue;
      const cv::Vec3f in = input.at<cv::Vec3f>(y, x);
      real.at<cv::Vec4f>(y, x) = cv::Vec4f(in[0], in[1], in[2], 1.0f);
      model.at<cv::Vec3f>(y, x) = w.composite.at<cv::Vec3f>(y, x);
    }
  }
  int factor = 1;
  const cv::Mat real_low = LowPassDown(real, sigma_px, &factor);
  const cv::Mat model_low = LowPassDown(model, sigma_px, &factor);
  cv::Mat gain_low(real_low.size(), CV_32FC3);
  for (int y = 0; y < gain_low.rows; ++y) {
    for (int x = 0; x < gain_low.cols; ++x) {
      const cv::Vec4f r = real_low.at<cv::Vec4f>(y, x);
      const cv::Vec3f m = model_low.at<cv::Vec3f>(y, x);
      for (int k = 0; k < 3; ++k) {
        gain_low.at<cv::Vec3f>(y, x)[k] =
            r[3] >= 0.05f && m[k] > 0.01f * r[3] ? std::clamp(r[k] / m[k], 0.2f, 5.0f) : 1.0f;
      }
    }
  }
  const cv::Mat gain = LowPassUp(gain_low, w.composite.size(), factor);
  cv::Mat out = w.composite.clone();
  for (int y = 0; y < out.rows; ++y) {
    for (int x = 0; x < out.cols; ++x) {
      if (w.coverage.at<uint8_t>(y, x) == 0) continue;
      out.at<cv::Vec3f>(y, x) = out.at<cv::Vec3f>(y, x).mul(gain.at<cv::Vec3f>(y, x));
    }
  }
  return out;
}

TEST(TransferShading, MatchesTheWholeImageLowPass) {
  // A region whose size is no multiple of the low-pass's factor, the object touching its
  // right and bottom borders (where the factor's padding repeats the border pixels), its
  // rim partly covered; the input a shaded copy of the composite plus noise.
  const int width = 93, height = 71;
  cv::RNG rng(7);
  VirtualImage w;
  w.composite.create(height, width, CV_32FC3);
  rng.fill(w.composite, cv::RNG::UNIFORM, 0.2, 0.9);
  w.coverage = cv::Mat(height, width, CV_8UC1, cv::Scalar(0));
  cv::ellipse(w.coverage, cv::Point(70, 50), cv::Size(40, 30), 0, 0, 360, cv::Scalar(2), 3);
  cv::ellipse(w.coverage, cv::Point(70, 50), cv::Size(40, 30), 0, 0, 360, cv::Scalar(4), -1);
  w.mask = w.coverage > 0;
  cv::Mat input(height, width, CV_32FC3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const float shade = 0.6f + 0.5f * float(x) / width;
      input.at<cv::Vec3f>(y, x) = w.composite.at<cv::Vec3f>(y, x) * shade;
    }
  }
  cv::Mat noise(input.size(), input.type());
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 0.02);
  input += noise;
  const cv::Rect rendered(25, 15, width - 25, height - 15);
  for (const int level : {0, 1, 2}) {
    PreprocessOptions options;
    const double sigma = options.ShadingSigmaAtLevel(level);
    ASSERT_GE(LowPassFactor(w.composite.size(), sigma), 2) << "level " << level;
    VirtualImage shaded;
    shaded.composite = w.composite.clone();
    shaded.coverage = w.coverage;
    shaded.mask = w.mask;
    TransferShading(input, options, level, rendered, &shaded);
    const cv::Mat expected = ReferenceShading(input, w, sigma);
    EXPECT_LT(cv::norm(shaded.composite, expected, cv::NORM_INF), 1e-5) << "level " << level;
    // The shading was transferred: the covered pixels moved towards the input.
    EXPECT_LT(cv::norm(shaded.composite, input, cv::NORM_L1, w.mask),
              0.5 * cv::norm(w.composite, input, cv::NORM_L1, w.mask))
        << "level " << level;
  }
}

}  // namespace
}  // namespace unseen
