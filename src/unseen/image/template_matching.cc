// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/image/template_matching.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "unseen/util/error.h"

namespace unseen {
namespace {

// `m` (single channel) converted to CV_64F in the top-left corner of a zero image of `size`,
// transformed (CCS-packed spectrum; only its first `nonzero_rows` rows are non-zero).
cv::Mat PaddedSpectrum(const cv::Mat& m, cv::Size size) {
  cv::Mat padded = cv::Mat::zeros(size, CV_64FC1);
  m.convertTo(padded(cv::Rect(0, 0, m.cols, m.rows)), CV_64F);
  cv::Mat spectrum;
  cv::dft(padded, spectrum, 0, m.rows);
  return spectrum;
}

// The real correlation whose spectrum is a * conj(b), its first `rows` rows.
cv::Mat Correlation(const cv::Mat& a, const cv::Mat& b, int rows) {
  cv::Mat product, out;
  cv::mulSpectrums(a, b, product, 0, /*conjB=*/true);
  cv::dft(product, out, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT, rows);
  return out;
}

}  // namespace

MaskedTemplateMatcher::MaskedTemplateMatcher(const cv::Mat& image, cv::Size template_size)
    : image_size_(image.size()), template_size_(template_size) {
  UNSEEN_CHECK(!image.empty() && image.channels() <= 4 &&
                   (image.depth() == CV_32F || image.depth() == CV_64F),
               "MaskedTemplateMatcher: the image must be non-empty CV_32F or CV_64F of 1-4 "
               "channels (type {})",
               image.type());
  UNSEEN_CHECK(template_size.width >= 1 && template_size.height >= 1 &&
                   template_size.width <= image.cols && template_size.height <= image.rows,
               "MaskedTemplateMatcher: template {}x{} does not fit the {}x{} image",
               template_size.width, template_size.height, image.cols, image.rows);
  // Offsets u of the valid range and template pixels x reach u + x <= size - 1: a DFT of
  // the image's own size does not wrap them around.
  dft_size_ = cv::Size(cv::getOptimalDFTSize(image.cols), cv::getOptimalDFTSize(image.rows));
  std::vector<cv::Mat> channels;
  cv::split(image, channels);
  cv::Mat squares = cv::Mat::zeros(image.size(), CV_64FC1);
  for (const cv::Mat& channel : channels) {
    cv::Mat f;
    channel.convertTo(f, CV_64F);
    image_spectra_.push_back(PaddedSpectrum(f, dft_size_));
    squares += f.mul(f);
  }
  squares_spectrum_ = PaddedSpectrum(squares, dft_size_);
}

cv::Mat MaskedTemplateMatcher::Match(const cv::Mat& templ, const cv::Mat& mask) const {
  return Match(Prepare(templ, mask));
}

MaskedTemplateMatcher::Prepared MaskedTemplateMatcher::Prepare(const cv::Mat& templ,
                                                               const cv::Mat& mask) const {
  const int channels = static_cast<int>(image_spectra_.size());
  UNSEEN_CHECK(templ.size() == template_size_ && templ.channels() == channels &&
                   (templ.depth() == CV_32F || templ.depth() == CV_64F),
               "MaskedTemplateMatcher: the template must be CV_32F or CV_64F of {} channel(s) "
               "and {}x{} (type {}, {}x{})",
               channels, template_size_.width, template_size_.height, templ.type(), templ.cols,
               templ.rows);
  UNSEEN_CHECK(mask.size() == template_size_ && mask.type() == CV_8UC1,
               "MaskedTemplateMatcher: the mask must be CV_8UC1 of {}x{} (type {}, {}x{})",
               template_size_.width, template_size_.height, mask.type(), mask.cols, mask.rows);
  Prepared prepared;
  prepared.dft_size = dft_size_;
  prepared.template_size = template_size_;
  cv::Mat m;
  cv::compare(mask, 0, m, cv::CMP_GT);
  m.convertTo(m, CV_64F, 1.0 / 255.0);
  prepared.n = cv::sum(m)[0];
  if (prepared.n < 1.0) return prepared;
  std::vector<cv::Mat> planes;
  cv::split(templ, planes);
  std::vector<cv::Mat> centred(planes.size());
  for (size_t k = 0; k < planes.size(); ++k) {
    cv::Mat t;
    planes[k].convertTo(t, CV_64F);
    const double mean = cv::sum(t.mul(m))[0] / prepared.n;
    centred[k] = (t - mean).mul(m);
    prepared.centred_energy += cv::sum(centred[k].mul(centred[k]))[0];
  }
  if (!(prepared.centred_energy > 1e-20)) return prepared;
  prepared.mask_spectrum = PaddedSpectrum(m, dft_size_);
  for (const cv::Mat& c : centred) prepared.centred_spectra.push_back(PaddedSpectrum(c, dft_size_));
  return prepared;
}

cv::Mat MaskedTemplateMatcher::Match(const Prepared& prepared) const {
  UNSEEN_CHECK(Fits(prepared),
               "MaskedTemplateMatcher::Match: a template prepared for {}x{} templates and a "
               "{}x{} transform, this matcher's are {}x{} and {}x{}",
               prepared.template_size.width, prepared.template_size.height, prepared.dft_size.width,
               prepared.dft_size.height, template_size_.width, template_size_.height,
               dft_size_.width, dft_size_.height);
  const int rows = image_size_.height - template_size_.height + 1;
  const int cols = image_size_.width - template_size_.width + 1;
  cv::Mat scores(rows, cols, CV_32FC1, cv::Scalar(-1.0f));
  if (prepared.centred_spectra.empty()) return scores;
  const double n = prepared.n;
  const double centred_energy = prepared.centred_energy;
  // Sum over the channels of F's correlation with T' (summed as spectra: one inverse
  // transform) and of the squares of F's sums under the mask (one each).
  cv::Mat cross_spectrum = cv::Mat::zeros(image_spectra_[0].size(), CV_64FC1);
  cv::Mat sum_squares = cv::Mat::zeros(rows, cols, CV_64FC1);
  for (size_t k = 0; k < image_spectra_.size(); ++k) {
    cv::Mat product;
    cv::mulSpectrums(image_spectra_[k], prepared.centred_spectra[k], product, 0, /*conjB=*/true);
    cross_spectrum += product;
    const cv::Mat sums = Correlation(image_spectra_[k], prepared.mask_spectrum, rows);
    sum_squares += sums(cv::Rect(0, 0, cols, rows)).mul(sums(cv::Rect(0, 0, cols, rows)));
  }
  cv::Mat cross;
  cv::dft(cross_spectrum, cross, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT, rows);
  const cv::Mat squares = Correlation(squares_spectrum_, prepared.mask_spectrum, rows);
  for (int y = 0; y < rows; ++y) {
    const double* c = cross.ptr<double>(y);
    const double* s2 = sum_squares.ptr<double>(y);
    const double* q = squares.ptr<double>(y);
    float* out = scores.ptr<float>(y);
    for (int x = 0; x < cols; ++x) {
      const double variance = q[x] - s2[x] / n;
      const double denominator = variance * centred_energy;
      // Relative to the squares' scale: below it the variance is the transforms' rounding.
      if (!(denominator > 1e-12 * std::max(q[x], 1e-12) * centred_energy)) continue;
      out[x] = static_cast<float>(std::clamp(c[x] / std::sqrt(denominator), -1.0, 1.0));
    }
  }
  return scores;
}

}  // namespace unseen
