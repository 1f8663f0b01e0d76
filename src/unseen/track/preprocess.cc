// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/preprocess.h"

#include <algorithm>
#include <cmath>

#include "unseen/image/filters.h"
#include "unseen/util/error.h"

namespace unseen {

void PreprocessOptions::Check() const {
  UNSEEN_CHECK(linf_sigma_px > 0.0 && std::isfinite(linf_sigma_px),
               "preprocess.linf_sigma_px {} must be > 0", linf_sigma_px);
  UNSEEN_CHECK(min_linf_sigma_px > 0.0 && std::isfinite(min_linf_sigma_px),
               "preprocess.min_linf_sigma_px {} must be > 0", min_linf_sigma_px);
  UNSEEN_CHECK(linf_epsilon > 0.0 && linf_epsilon < 10.0,
               "preprocess.linf_epsilon {} must be in (0, 10)", linf_epsilon);
  UNSEEN_CHECK(blur_sigma_px > 0.0 && blur_sigma_px <= 10.0,
               "preprocess.blur_sigma_px {} must be in (0, 10]", blur_sigma_px);
  UNSEEN_CHECK(silhouette_gamma >= 1.0 && silhouette_gamma <= 3.0,
               "preprocess.silhouette_gamma {} must be in [1, 3]", silhouette_gamma);
  UNSEEN_CHECK(shading_sigma_px > 0.0 && std::isfinite(shading_sigma_px),
               "preprocess.shading_sigma_px {} must be > 0", shading_sigma_px);
  UNSEEN_CHECK(background_band_px >= 0 && background_band_px <= 16,
               "preprocess.background_band_px {} must be in [0, 16]", background_band_px);
  UNSEEN_CHECK(background_sigma_px > 0.0 && background_sigma_px <= 20.0,
               "preprocess.background_sigma_px {} must be in (0, 20]", background_sigma_px);
}

double PreprocessOptions::ShadingSigmaAtLevel(int level) const {
  return std::max(shading_sigma_px / double(1 << level), min_linf_sigma_px);
}

double PreprocessOptions::LinfSigmaAtLevel(int level) const {
  return std::max(linf_sigma_px / double(1 << level), min_linf_sigma_px);
}

void Preprocess(const cv::Mat& image, const PreprocessOptions& options, int level,
                bool with_gradients, PreprocessedImage* out) {
  UNSEEN_CHECK(!image.empty() && image.type() == CV_32FC3,
               "Preprocess: image must be non-empty CV_32FC3 (type {})", image.type());
  if (options.use_linf) {
    out->blurred = GaussianBlurred(
        LocalIlluminationNormalize(image, options.LinfSigmaAtLevel(level), options.linf_epsilon),
        options.blur_sigma_px);
  } else {
    out->blurred = GaussianBlurred(image, options.blur_sigma_px);
  }
  if (with_gradients) CentralGradients(out->blurred, &out->gx, &out->gy);
}

}  // namespace unseen
