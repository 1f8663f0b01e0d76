// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Region-of-interest selection (SPEC 4.3, thesis (2.7)-(2.12)): of the image's regions
// (from motion segmentation, or the connected parts of the interest map), the object of
// interest is the candidate with the highest mean interest. For each region R: Z = its
// pixels with interest above tau_S, W = those of Z with texturedness above tau_T (depth is
// reliable there); TotalArea |R|, InterestArea |Z|, TotalInterest sum_Z S, MeanInterest =
// TotalInterest / TotalArea, DepthPixelArea |W|, MeanDepth over W, the bounding box and,
// back-projected at MeanDepth, its physical width and height. A region is a candidate when
// its size, interest and area pass the thresholds below; the object is the candidate of
// highest MeanInterest (or TotalInterest, by option); no candidate is a status ("no object
// of interest this frame"), not an error.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "unseen/camera/camera.h"

namespace unseen {

struct RegionSelectionOptions {
  double min_interest = 0.5;         // tau_S: a pixel of interest has S above this
  double min_texturedness = 0.0;     // tau_T: depth counts on pixels above this
  int min_area_px = 100;             // TotalArea
  double min_interest_share = 0.3;   // tau_A: InterestArea / TotalArea
  double min_mean_interest = 0.2;    // MeanInterest
  double min_total_interest = 50.0;  // TotalInterest
  double min_size_m = 0.01;          // physical width and height, when there is depth
  double max_size_m = 0.6;
  // Which candidate is the object: the thesis's highest MeanInterest, or the highest
  // TotalInterest (a slowly moving textured object's motion mask is in pieces, each with
  // a high mean; the object's pieces joined outweigh a speck of noise).
  bool rank_by_total_interest = false;
  void Check() const;
};

struct RegionCandidate {
  int label = 0;  // in the label image
  PixelRect box;  // bounding box
  int total_area = 0, interest_area = 0, depth_area = 0;
  double total_interest = 0.0, mean_interest = 0.0;
  double mean_depth_m = 0.0;             // 0 without depth
  double width_m = 0.0, height_m = 0.0;  // 0 without depth
  bool candidate = false;
  std::string rejected;  // why not, when not a candidate
};

struct RegionSelection {
  std::vector<RegionCandidate> regions;  // every labelled region, by label
  int selected = -1;                     // index into `regions`; -1: no object of interest
  bool found() const { return selected >= 0; }
  const RegionCandidate& object() const { return regions[selected]; }
};

// `labels` CV_32SC1 (0 = no region), `interest` CV_32FC1 in [0, 1]; `texturedness`
// (CV_32FC1) and `depth` (CV_32FC1 metres, 0 = none) of the same size, or empty: without
// texturedness every pixel counts for depth, without depth there is no size test.
// Throws unseen::Error for maps of the wrong type or size, or invalid options.
RegionSelection SelectRegion(const cv::Mat& labels, const cv::Mat& interest,
                             const cv::Mat& texturedness, const cv::Mat& depth,
                             const PinholeCamera& camera, const RegionSelectionOptions& options);

// Regions from the interest map alone (until motion segmentation): the 8-connected parts
// of S > min_interest after a closing of `close_px` (odd; 1 = none) that joins the pieces
// of a moving object's mask (21 px: measured on the 512x256 development sequences, where 5
// left a slowly moving cube in up to 20 pieces). CV_32SC1 labels, 0 = none.
cv::Mat InterestRegions(const cv::Mat& interest, double min_interest, int close_px = 21);

}  // namespace unseen
