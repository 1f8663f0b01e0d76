// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// A colour co-occurrence histogram interest filter (SPEC 4.1; Chang & Krumm 1999, "Object
// recognition with color cooccurrence histograms"; Ekvall, Hoffmann & Kragic 2005). The
// model is the histogram of (colour, colour, distance) over the pixel pairs of a reference
// region; a frame's windows of the region's size are scored by histogram intersection
// with it, and the score becomes interest on the pixels each window covers.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "unseen/select/interest_filter.h"

namespace unseen {

struct CooccurrenceFilterOptions {
  // Quantised colours: k-means centres (BGR) of the reference region's pixels.
  int colours = 12;
  // A pixel farther than this (BGR distance, channels in [0, 1]) from every centre is
  // "other": its pairs count in a window's total but match no model bin, so background
  // colours lower the score instead of being forced onto the nearest object colour.
  double max_colour_distance = 0.2;
  // Edges of the distance bins, px, increasing; bin i holds separations in [e_i, e_i+1),
  // sampled in 4 directions at the bin's middle distance.
  std::vector<double> distance_edges_px = {1.0, 3.0, 6.0, 12.0};
  int pixel_step = 2;  // the first pixel of each pair on this grid, px
  int stride_px = 8;   // window positions and cell size, px
  // Window sizes as multiples of the reference region's bounding box.
  std::vector<double> scales = {1.0};
  // Interest = clamp((score - min_score) / (full_score - min_score), 0, 1), score the
  // histogram intersection in [0, 1]. Measured at the defaults: the object ~0.75 (a pair
  // sample never reaches 1), cluttered backgrounds below ~0.45.
  double min_score = 0.4;
  double full_score = 0.7;
  // Optional: learn at construction from this image (any path; the YAML bank resolves it)
  // and the object's rectangle in it, px (all zero: the whole image). An empty path leaves
  // the filter to Learn().
  std::string reference_image;
  cv::Rect reference_rect;
  void Check() const;
};

class CooccurrenceFilter : public InterestFilter {
 public:
  // Learns from options.reference_image when it is given; throws unseen::Error naming the
  // path when it cannot be read or the rectangle does not lie inside it.
  explicit CooccurrenceFilter(const CooccurrenceFilterOptions& options);
  std::string name() const override { return "cooccurrence"; }

  // The model from `image` (any type ToFloatBgr reads) where `mask` (CV_8UC1, same size)
  // is non-zero; windows get the size of the mask's bounding box. Throws unseen::Error for
  // an empty mask or one too small to hold a pair, leaving the filter unlearnt.
  void Learn(const cv::Mat& image, const cv::Mat& mask);
  void Learn(const cv::Mat& image, const cv::Rect& rect);

  // Interest from windows centred on pixels whose interest is above zero; each pixel gets
  // the best interest of the windows covering it (bilinearly smoothed over cells). Leaves
  // no interest before Learn(), or where the image is smaller than a window.
  void Apply(const FilterFrame& frame, cv::Mat* interest) override;
  bool ready() const override { return !model_.empty(); }

  // The reference region's bounding box, px (empty before Learn()).
  const cv::Size& window_size() const { return window_size_; }

 private:
  struct Offset {
    int dx, dy, bin;
  };
  // Per pixel: its colour index in [0, colours], `colours` meaning "other".
  cv::Mat Quantise(const cv::Mat& bgr) const;
  // The pair counts of the pairs whose first pixel lies in each cell of `cell_px`, as an
  // integral over the cell grid: (rows + 1) x (cols + 1) x (bins + 1) ints, the last one
  // of each cell the total.
  std::vector<int> IntegralCellHistograms(const cv::Mat& labels, int cell_px, cv::Size* grid) const;

  CooccurrenceFilterOptions options_;
  std::vector<cv::Vec3f> centres_;  // BGR in [0, 1]
  std::vector<unsigned char> lut_;  // 5 bits a channel: colour index
  std::vector<int> pair_bin_;       // (c1, c2): bin of the pair, -1 with "other"
  std::vector<Offset> offsets_;
  std::vector<double> model_;  // normalised histogram over the pair-distance bins
  cv::Size window_size_;       // the reference region's bounding box, px
};

}  // namespace unseen
