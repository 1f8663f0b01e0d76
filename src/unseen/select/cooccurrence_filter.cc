// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// How a frame is scored fast enough to run on every frame: the frame's pairs are counted
// once into cells of stride_px (a pair belongs to the cell of its first pixel, on a
// pixel_step grid, with 4 sampled directions per distance bin instead of every pair),
// the cells' histograms are integrated over the cell grid, and a window's histogram is
// then 4 look-ups a bin whatever its size (an integral histogram, Porikli 2005). Pairs
// whose second pixel lies outside the window still count: a few per cent of a window's
// pairs for the default distances, which lowers the best score a little (full_score < 1).
//
// Quantisation: k-means of the reference region's colours (Chang & Krumm's choice), not a
// fixed grid: a few colours fitted to the object separate it better than the same number
// of fixed bins, most of which it does not use; colours far from every centre are "other"
// (see max_colour_distance). A 32^3 look-up table quantises a frame in one pass.
#include "unseen/select/cooccurrence_filter.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "unseen/image/image_io.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

constexpr int kLutBits = 5;
constexpr int kLutSide = 1 << kLutBits;

// A channel in [0, 1] (anything else clamped, NaN to 0) as its look-up table coordinate.
inline int LutCoordinate(float v) {
  return v > 0.0f ? (v < 1.0f ? static_cast<int>(v * kLutSide) : kLutSide - 1) : 0;
}

inline int LutIndex(const cv::Vec3f& bgr) {
  return (LutCoordinate(bgr[0]) << (2 * kLutBits)) | (LutCoordinate(bgr[1]) << kLutBits) |
         LutCoordinate(bgr[2]);
}

}  // namespace

void CooccurrenceFilterOptions::Check() const {
  UNSEEN_CHECK(colours >= 2 && colours <= 32, "cooccurrence filter: colours {} not in [2, 32]",
               colours);
  UNSEEN_CHECK(max_colour_distance > 0.0 && std::isfinite(max_colour_distance),
               "cooccurrence filter: max_colour_distance {} must be > 0", max_colour_distance);
  UNSEEN_CHECK(distance_edges_px.size() >= 2 && distance_edges_px.size() <= 7,
               "cooccurrence filter: distance_edges_px has {} edges; give 2 to 7 (1 to 6 bins)",
               distance_edges_px.size());
  for (size_t i = 0; i < distance_edges_px.size(); ++i) {
    const double e = distance_edges_px[i];
    UNSEEN_CHECK(
        std::isfinite(e) && e >= 1.0 && e <= 64.0 && (i == 0 || e > distance_edges_px[i - 1]),
        "cooccurrence filter: distance_edges_px[{}] = {} must be in [1, 64] px and "
        "above the previous edge",
        i, e);
  }
  UNSEEN_CHECK(pixel_step >= 1 && pixel_step <= 16,
               "cooccurrence filter: pixel_step {} not in [1, 16] px", pixel_step);
  UNSEEN_CHECK(stride_px >= 4 && stride_px <= 64,
               "cooccurrence filter: stride_px {} not in [4, 64] px", stride_px);
  UNSEEN_CHECK(!scales.empty() && scales.size() <= 8,
               "cooccurrence filter: give 1 to 8 scales ({} given)", scales.size());
  for (double s : scales) {
    UNSEEN_CHECK(s >= 0.25 && s <= 4.0, "cooccurrence filter: scale {} not in [0.25, 4]", s);
  }
  UNSEEN_CHECK(min_score >= 0.0 && min_score < full_score && full_score <= 1.0,
               "cooccurrence filter: need 0 <= min_score < full_score <= 1 (min_score {}, "
               "full_score {})",
               min_score, full_score);
  if (!reference_image.empty() && reference_rect != cv::Rect()) {
    UNSEEN_CHECK(reference_rect.x >= 0 && reference_rect.y >= 0 && reference_rect.width > 0 &&
                     reference_rect.height > 0,
                 "cooccurrence filter: reference_rect [{}, {}, {}, {}] must have x, y >= 0 and "
                 "a positive size (or be all zero: the whole image)",
                 reference_rect.x, reference_rect.y, reference_rect.width, reference_rect.height);
  }
}

CooccurrenceFilter::CooccurrenceFilter(const CooccurrenceFilterOptions& options)
    : options_(options) {
  options_.Check();
  const std::vector<double>& edges = options_.distance_edges_px;
  const double diagonal = std::sqrt(0.5);
  for (int bin = 0; bin + 1 < static_cast<int>(edges.size()); ++bin) {
    const double r = 0.5 * (edges[bin] + edges[bin + 1]);
    const int axis = static_cast<int>(std::lround(r));
    const int diag = std::max(1, static_cast<int>(std::lround(r * diagonal)));
    // Pairs are unordered: these 4 directions stand for all 8.
    offsets_.push_back({axis, 0, bin});
    offsets_.push_back({0, axis, bin});
    offsets_.push_back({diag, diag, bin});
    offsets_.push_back({-diag, diag, bin});
  }
  if (options_.reference_image.empty()) return;
  const cv::Mat image = LoadColorImage(options_.reference_image);
  const cv::Rect r = options_.reference_rect == cv::Rect() ? cv::Rect(0, 0, image.cols, image.rows)
                                                           : options_.reference_rect;
  UNSEEN_CHECK(static_cast<int64_t>(r.x) + r.width <= image.cols &&
                   static_cast<int64_t>(r.y) + r.height <= image.rows,
               "cooccurrence filter: reference_rect [{}, {}, {}, {}] is not inside the {}x{} "
               "image {}",
               r.x, r.y, r.width, r.height, image.cols, image.rows, options_.reference_image);
  Learn(image, r);
}

void CooccurrenceFilter::Learn(const cv::Mat& image, const cv::Rect& rect) {
  UNSEEN_CHECK(!image.empty() && rect.width > 0 && rect.height > 0 &&
                   (rect & cv::Rect(0, 0, image.cols, image.rows)) == rect,
               "cooccurrence filter: the rectangle [{}, {}, {}, {}] is not inside the {}x{} "
               "reference image",
               rect.x, rect.y, rect.width, rect.height, image.cols, image.rows);
  cv::Mat mask(image.size(), CV_8UC1, cv::Scalar(0));
  mask(rect).setTo(255);
  Learn(image, mask);
}

void CooccurrenceFilter::Learn(const cv::Mat& image, const cv::Mat& mask) {
  model_.clear();  // unlearnt until the new model is complete
  const cv::Mat bgr = ToFloatBgr(image, "cooccurrence filter reference");
  UNSEEN_CHECK(mask.type() == CV_8UC1 && mask.size() == bgr.size(),
               "cooccurrence filter: the reference mask must be CV_8UC1 of the image's {}x{} "
               "pixels",
               bgr.cols, bgr.rows);
  const int count = cv::countNonZero(mask);
  UNSEEN_CHECK(count > 0, "cooccurrence filter: the reference mask is empty");

  // k-means of (at most ~20 000 of) the region's colours, with a fixed seed.
  const int every = std::max(1, count / 20000);
  std::vector<cv::Vec3f> samples;
  int seen = 0;
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      if (mask.at<uchar>(y, x) && seen++ % every == 0) samples.push_back(bgr.at<cv::Vec3f>(y, x));
    }
  }
  const int k = std::min(options_.colours, static_cast<int>(samples.size()));
  cv::Mat labels, centres;
  cv::RNG& rng = cv::theRNG();
  const uint64 saved_state = rng.state;
  rng.state = 0x5eed;
  cv::kmeans(cv::Mat(samples).reshape(1), k, labels,
             cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 30, 1e-4), 3,
             cv::KMEANS_PP_CENTERS, centres);
  rng.state = saved_state;
  centres_.clear();
  for (int i = 0; i < centres.rows; ++i) centres_.push_back(centres.at<cv::Vec3f>(i));

  // The look-up table: nearest centre of each 5-bit cell's centre, or "other".
  const int other = static_cast<int>(centres_.size());
  const float max_d2 =
      static_cast<float>(options_.max_colour_distance * options_.max_colour_distance);
  lut_.assign(kLutSide * kLutSide * kLutSide, static_cast<unsigned char>(other));
  for (int b = 0; b < kLutSide; ++b) {
    for (int g = 0; g < kLutSide; ++g) {
      for (int r = 0; r < kLutSide; ++r) {
        const cv::Vec3f c((b + 0.5f) / kLutSide, (g + 0.5f) / kLutSide, (r + 0.5f) / kLutSide);
        float best = max_d2;
        for (int i = 0; i < other; ++i) {
          const cv::Vec3f d = c - centres_[i];
          const float d2 = d.dot(d);
          if (d2 <= best) {
            best = d2;
            lut_[LutIndex(c)] = static_cast<unsigned char>(i);
          }
        }
      }
    }
  }
  pair_bin_.assign((other + 1) * (other + 1), -1);
  int pairs = 0;
  for (int a = 0; a < other; ++a) {
    for (int b = a; b < other; ++b) {
      pair_bin_[a * (other + 1) + b] = pair_bin_[b * (other + 1) + a] = pairs++;
    }
  }

  // The model: pairs with both pixels in the mask, normalised by their number.
  const int distance_bins = static_cast<int>(options_.distance_edges_px.size()) - 1;
  const cv::Mat quantised = Quantise(bgr);
  std::vector<double> histogram(pairs * distance_bins, 0.0);
  double total = 0.0;
  for (int y = 0; y < bgr.rows; y += options_.pixel_step) {
    for (int x = 0; x < bgr.cols; x += options_.pixel_step) {
      if (!mask.at<uchar>(y, x)) continue;
      const int c1 = quantised.at<uchar>(y, x);
      for (const Offset& o : offsets_) {
        const int x2 = x + o.dx, y2 = y + o.dy;
        if (x2 < 0 || x2 >= bgr.cols || y2 >= bgr.rows || !mask.at<uchar>(y2, x2)) continue;
        total += 1.0;
        const int pair = pair_bin_[c1 * (other + 1) + quantised.at<uchar>(y2, x2)];
        if (pair >= 0) histogram[pair * distance_bins + o.bin] += 1.0;
      }
    }
  }
  UNSEEN_CHECK(total > 0.0,
               "cooccurrence filter: the reference region holds no pixel pairs {} px apart "
               "(too small or too thin)",
               options_.distance_edges_px.back());
  for (double& h : histogram) h /= total;
  model_ = std::move(histogram);
  window_size_ = cv::boundingRect(mask).size();
}

cv::Mat CooccurrenceFilter::Quantise(const cv::Mat& bgr) const {
  cv::Mat labels(bgr.size(), CV_8UC1);
  for (int y = 0; y < bgr.rows; ++y) {
    const cv::Vec3f* px = bgr.ptr<cv::Vec3f>(y);
    uchar* l = labels.ptr<uchar>(y);
    for (int x = 0; x < bgr.cols; ++x) l[x] = lut_[LutIndex(px[x])];
  }
  return labels;
}

std::vector<int> CooccurrenceFilter::IntegralCellHistograms(const cv::Mat& labels, int cell_px,
                                                            cv::Size* grid) const {
  const int colours = static_cast<int>(centres_.size()) + 1;
  const int bins = static_cast<int>(model_.size()), stride = bins + 1;
  const int distance_bins = static_cast<int>(options_.distance_edges_px.size()) - 1;
  const int gw = (labels.cols + cell_px - 1) / cell_px, gh = (labels.rows + cell_px - 1) / cell_px;
  *grid = cv::Size(gw, gh);
  const size_t row_stride = static_cast<size_t>(gw + 1) * stride;
  std::vector<int> sums(static_cast<size_t>(gh + 1) * row_stride, 0);
  // Counts of each cell at (gy + 1, gx + 1).
  for (int y = 0; y < labels.rows; y += options_.pixel_step) {
    const uchar* row = labels.ptr<uchar>(y);
    int* cell_row = sums.data() + (y / cell_px + 1) * row_stride + stride;
    for (int x = 0; x < labels.cols; x += options_.pixel_step) {
      int* cell = cell_row + (x / cell_px) * stride;
      const int* pair_of = pair_bin_.data() + row[x] * colours;
      for (const Offset& o : offsets_) {
        const int x2 = x + o.dx, y2 = y + o.dy;
        if (x2 < 0 || x2 >= labels.cols || y2 >= labels.rows) continue;
        ++cell[bins];
        const int pair = pair_of[labels.ptr<uchar>(y2)[x2]];
        if (pair >= 0) ++cell[pair * distance_bins + o.bin];
      }
    }
  }
  // Integrate: along each row, then down the columns.
  for (int gy = 1; gy <= gh; ++gy) {
    int* row = sums.data() + gy * row_stride;
    for (int gx = 2; gx <= gw; ++gx) {
      for (int b = 0; b < stride; ++b) row[gx * stride + b] += row[(gx - 1) * stride + b];
    }
    const int* above = row - row_stride;
    if (gy > 1) {
      for (size_t i = stride; i < row_stride; ++i) row[i] += above[i];
    }
  }
  return sums;
}

void CooccurrenceFilter::Apply(const FilterFrame& frame, cv::Mat* interest) {
  UNSEEN_CHECK(frame.image.type() == CV_32FC3 && !frame.image.empty(),
               "cooccurrence filter: the image must be CV_32FC3 BGR in [0, 1] (type {})",
               frame.image.type());
  UNSEEN_CHECK(interest->type() == CV_32FC1 && interest->size() == frame.image.size(),
               "cooccurrence filter: the interest map must be CV_32FC1 of the image's {}x{} "
               "pixels",
               frame.image.cols, frame.image.rows);
  if (!ready()) {
    interest->setTo(0.0f);
    return;
  }
  if (cv::countNonZero(*interest > 0.0f) == 0) return;
  const int cell = options_.stride_px;
  cv::Size grid;
  const std::vector<int> sums = IntegralCellHistograms(Quantise(frame.image), cell, &grid);
  const int bins = static_cast<int>(model_.size()), stride = bins + 1;
  const size_t row_stride = static_cast<size_t>(grid.width + 1) * stride;
  const double range = options_.full_score - options_.min_score;

  // Per cell, the best interest of the windows covering it, over the scales.
  cv::Mat best(grid, CV_32FC1, cv::Scalar(0.0f));
  for (double scale : options_.scales) {
    const int ww = std::max(1, static_cast<int>(std::lround(window_size_.width * scale / cell)));
    const int wh = std::max(1, static_cast<int>(std::lround(window_size_.height * scale / cell)));
    if (ww > grid.width || wh > grid.height) continue;
    cv::Mat window_interest(grid, CV_32FC1, cv::Scalar(0.0f));  // at the top-left cell
    for (int wy = 0; wy + wh <= grid.height; ++wy) {
      const int cy = std::min(frame.image.rows - 1, (2 * wy + wh) * cell / 2);
      for (int wx = 0; wx + ww <= grid.width; ++wx) {
        const int cx = std::min(frame.image.cols - 1, (2 * wx + ww) * cell / 2);
        if (!(interest->at<float>(cy, cx) > 0.0f)) continue;
        const int* a = sums.data() + wy * row_stride + wx * stride;
        const int* b = a + ww * stride;
        const int* c = a + wh * row_stride;
        const int* d = c + ww * stride;
        const double total = d[bins] - b[bins] - c[bins] + a[bins];
        if (total <= 0.0) continue;
        double score = 0.0;  // histogram intersection, sum_b min(h_b, m_b)
        for (int i = 0; i < bins; ++i) {
          const int n = d[i] - b[i] - c[i] + a[i];
          if (n > 0) score += std::min(n / total, model_[i]);
        }
        window_interest.at<float>(wy, wx) =
            static_cast<float>(std::clamp((score - options_.min_score) / range, 0.0, 1.0));
      }
    }
    cv::Mat covered;
    cv::dilate(
        window_interest, covered,
        cv::getStructuringElement(cv::MORPH_RECT, cv::Size(ww, wh), cv::Point(ww - 1, wh - 1)),
        cv::Point(ww - 1, wh - 1));
    best = cv::max(best, covered);
  }
  cv::Mat calc;
  cv::resize(best, calc, cv::Size(grid.width * cell, grid.height * cell), 0.0, 0.0,
             cv::INTER_LINEAR);
  cv::multiply(*interest, calc(cv::Rect(0, 0, frame.image.cols, frame.image.rows)), *interest);
}

}  // namespace unseen
