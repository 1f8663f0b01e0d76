// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Masked normalised cross-correlation of one image with many templates of one size: the
// score of cv::matchTemplate(image, templ, result, cv::TM_CCOEFF_NORMED, mask) for a binary
// mask, computed by FFT with the image's transforms made once. Written here rather than
// calling OpenCV for every template because the re-acquisition correlates seven templates
// with the same window in every lost frame: OpenCV's masked matcher transforms the image
// again for each (three correlations per call), which made it three times slower there.
//
// For a template T, its mask M (n pixels), T' = M (T - mean of T over M) and an image F,
// at each offset u:
//   score(u) = sum_x F(u + x) T'(x) / sqrt(var_M(F, u) sum_x T'(x)^2),
//   var_M(F, u) = sum_x M(x) F(u + x)^2 - (sum_x M(x) F(u + x))^2 / n,
// three correlations, each a product of spectra (circular correlations of the zero-padded
// images; no offset of the valid range wraps around). Images of several channels (colour)
// are scored as OpenCV scores them, the channels together as one vector: the cross terms,
// the squares and the templates' energies summed over the channels, each channel centred
// on its own mean. The cross terms and the squares sum in the frequency domain, so C
// channels cost C + 2 inverse transforms a template instead of 3 C.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace unseen {

class MaskedTemplateMatcher {
 public:
  // `image`: CV_32F or CV_64F of 1 to 4 channels, non-empty; templates will be
  // `template_size`, at most the image's size. Throws unseen::Error otherwise.
  MaskedTemplateMatcher(const cv::Mat& image, cv::Size template_size);

  // Scores (CV_32FC1, (rows - h + 1) x (cols - w + 1), in [-1, 1]) of `templ` (CV_32F or
  // CV_64F of template_size, the image's channels) where `mask` (CV_8UC1 of template_size)
  // is non-zero; -1 at
  // offsets where the image has no variance under the mask, everywhere when the template
  // has none there or the mask is empty. Throws unseen::Error for other sizes or types.
  cv::Mat Match(const cv::Mat& templ, const cv::Mat& mask) const;

  // A template's transforms for matchers of this one's image and template sizes: a template
  // matched in many images (a series of frames) is transformed once.
  struct Prepared {
    cv::Size dft_size, template_size;
    // Per channel; empty: the template scores -1 everywhere.
    std::vector<cv::Mat> centred_spectra;
    cv::Mat mask_spectrum;
    double n = 0.0, centred_energy = 0.0;  // mask pixels, sum of T'^2 over the channels
  };
  // The transforms of `templ` under `mask` (as Match's); Match(Prepare(t, m)) == Match(t, m).
  Prepared Prepare(const cv::Mat& templ, const cv::Mat& mask) const;
  // Throws unseen::Error when `prepared` was made for another DFT or template size.
  cv::Mat Match(const Prepared& prepared) const;
  // Whether `prepared` was made for a matcher of this one's sizes.
  bool Fits(const Prepared& prepared) const {
    return prepared.dft_size == dft_size_ && prepared.template_size == template_size_;
  }

  cv::Size template_size() const { return template_size_; }

 private:
  cv::Size image_size_, template_size_;
  cv::Size dft_size_;
  // CCS-packed CV_64F spectra of each channel of F, and of F^2 summed over the channels.
  std::vector<cv::Mat> image_spectra_;
  cv::Mat squares_spectrum_;
};

}  // namespace unseen
