// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/region_modality.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "unseen/track/flow_jacobian.h"
#include "unseen/util/error.h"

namespace unseen {

void RegionModalityOptions::Check() const {
  UNSEEN_CHECK(bins_per_channel >= 2 && bins_per_channel <= 64 &&
                   (bins_per_channel & (bins_per_channel - 1)) == 0,
               "region.bins_per_channel {} must be a power of two in [2, 64]", bins_per_channel);
  UNSEEN_CHECK(max_lines >= 6 && max_lines <= 100000, "region.max_lines {} must be in [6, 1e5]",
               max_lines);
  UNSEEN_CHECK(line_px >= 2 && line_px <= 64, "region.line_px {} must be in [2, 64]", line_px);
  UNSEEN_CHECK(foreground_margin_px >= 0 && foreground_margin_px < line_px,
               "region.foreground_margin_px {} must be in [0, line_px = {})", foreground_margin_px,
               line_px);
  UNSEEN_CHECK(background_margin_px >= 0 && background_margin_px < line_px,
               "region.background_margin_px {} must be in [0, line_px = {})", background_margin_px,
               line_px);
  UNSEEN_CHECK(learn_rate > 0.0 && learn_rate <= 1.0, "region.learn_rate {} must be in (0, 1]",
               learn_rate);
  UNSEEN_CHECK(edge_contradiction_px >= 0.0 && std::isfinite(edge_contradiction_px),
               "region.edge_contradiction_px {} must be >= 0 (0: off)", edge_contradiction_px);
  UNSEEN_CHECK(min_sigma_px > 0.0 && min_sigma_px < max_sigma_px,
               "region: need 0 < min_sigma_px ({}) < max_sigma_px ({})", min_sigma_px,
               max_sigma_px);
  UNSEEN_CHECK(min_contrast >= 0.0 && min_contrast < 1.0, "region.min_contrast {} must be in [0, 1)",
               min_contrast);
  UNSEEN_CHECK(occluded_probe_px >= 0 && occluded_probe_px <= 64,
               "region.occluded_probe_px {} must be in [0, 64]", occluded_probe_px);
  residual.Check("region");
  UNSEEN_CHECK(min_start_edge_share >= 0.0 && min_start_edge_share <= 1.0,
               "region.min_start_edge_share {} must be in [0, 1]", min_start_edge_share);
  UNSEEN_CHECK(0.0 <= bad_agreement && bad_agreement < good_agreement && good_agreement <= 1.0,
               "region: need 0 <= bad_agreement ({}) < good_agreement ({}) <= 1", bad_agreement,
               good_agreement);
}

ColorHistograms::ColorHistograms(int bins_per_channel) : bins_(bins_per_channel) {
  shift_ = 0;
  while ((256 >> shift_) > bins_) ++shift_;
  Reset();
}

void ColorHistograms::Reset() {
  const size_t n = size_t(bins_) * bins_ * bins_;
  learnt_ = false;
  foreground_.assign(n, 0.0f);
  background_.assign(n, 0.0f);
  posterior_.assign(n, 0.5f);
  log_foreground_.assign(n, std::log(0.5f));
  log_background_.assign(n, std::log(0.5f));
  DiscardPending();
}

void ColorHistograms::DiscardPending() {
  const size_t n = size_t(bins_) * bins_ * bins_;
  pending_foreground_.assign(n, 0.0f);
  pending_background_.assign(n, 0.0f);
  pending_foreground_count_ = pending_background_count_ = 0.0;
}

int ColorHistograms::Bin(const float* bgr) const {
  int index = 0;
  for (int k = 0; k < 3; ++k) {
    const int v = std::clamp(static_cast<int>(bgr[k] * 255.0f + 0.5f), 0, 255) >> shift_;
    index = index * bins_ + v;
  }
  return index;
}

void ColorHistograms::Count(const float* bgr, bool foreground) {
  const int bin = Bin(bgr);
  if (foreground) {
    pending_foreground_[bin] += 1.0f;
    pending_foreground_count_ += 1.0;
  } else {
    pending_background_[bin] += 1.0f;
    pending_background_count_ += 1.0;
  }
}

void ColorHistograms::Commit(double rate) {
  constexpr double kMinSamples = 50.0;
  if (pending_foreground_count_ < kMinSamples || pending_background_count_ < kMinSamples) {
    DiscardPending();
    return;
  }
  const float r = learnt_ ? static_cast<float>(rate) : 1.0f;
  const float f = static_cast<float>(1.0 / pending_foreground_count_);
  const float b = static_cast<float>(1.0 / pending_background_count_);
  for (size_t i = 0; i < foreground_.size(); ++i) {
    foreground_[i] = (1.0f - r) * foreground_[i] + r * f * pending_foreground_[i];
    background_[i] = (1.0f - r) * background_[i] + r * b * pending_background_[i];
  }
  learnt_ = true;
  UpdatePosterior();
  DiscardPending();
}

void ColorHistograms::UpdatePosterior() {
  // A colour neither side has seen is undecided; a small floor keeps a colour seen on one
  // side only from being certain.
  const float floor = 1e-5f;
  for (size_t i = 0; i < posterior_.size(); ++i) {
    const float f = foreground_[i] + floor, b = background_[i] + floor;
    posterior_[i] = f / (f + b);
    const float p = std::clamp(posterior_[i], kMinPosterior, 1.0f - kMinPosterior);
    log_foreground_[i] = std::log(p);
    log_background_[i] = std::log(1.0f - p);
  }
}

RegionCounts& RegionCounts::operator+=(const RegionCounts& o) {
  lines += o.lines;
  used += o.used;
  pixels += o.pixels;
  agreeing += o.agreeing;
  edge_lines += o.edge_lines;
  occluded += o.occluded;
  overrun += o.overrun;
  return *this;
}

namespace {

struct ContourSample {
  int x, y;  // buffer pixel: the last object pixel
  float nx, ny;  // outward unit normal
};

// Boundary pixels of the mask (object pixels with a 4-neighbour outside it), at most
// `max_samples` spread evenly in raster order, with the outward normal from the object
// pixels around (5x5).
std::vector<ContourSample> SampleContour(const cv::Mat& mask, int max_samples) {
  const int width = mask.cols, height = mask.rows;
  std::vector<std::pair<int, int>> boundary;
  for (int y = 2; y < height - 2; ++y) {
    const uint8_t* m = mask.ptr<uint8_t>(y);
    const uint8_t* up = mask.ptr<uint8_t>(y - 1);
    const uint8_t* down = mask.ptr<uint8_t>(y + 1);
    for (int x = 2; x < width - 2; ++x) {
      if (!m[x]) continue;
      if (!m[x - 1] || !m[x + 1] || !up[x] || !down[x]) boundary.emplace_back(x, y);
    }
  }
  std::vector<ContourSample> out;
  if (boundary.empty()) return out;
  const double step = std::max(1.0, double(boundary.size()) / max_samples);
  for (double i = 0.5 * step; i < double(boundary.size()); i += step) {
    const auto [x, y] = boundary[static_cast<size_t>(i)];
    float sx = 0.0f, sy = 0.0f;
    for (int dy = -2; dy <= 2; ++dy) {
      const uint8_t* m = mask.ptr<uint8_t>(y + dy);
      for (int dx = -2; dx <= 2; ++dx) {
        if (m[x + dx]) {
          sx += float(dx);
          sy += float(dy);
        }
      }
    }
    const float norm = std::hypot(sx, sy);
    if (norm < 1e-3f) continue;  // a thin sliver: no direction
    out.push_back({x, y, -sx / norm, -sy / norm});
  }
  return out;
}

}  // namespace

void AddRegionEquations(const RegionModalityInput& in, const RegionModalityOptions& options,
                        bool learn, ColorHistograms* histograms, FlowEquations* out,
                        RegionCounts* counts) {
  const cv::Mat& image = *in.image;
  const cv::Mat& mask = *in.mask;
  const cv::Mat& depth = *in.rendered_depth;
  UNSEEN_CHECK(image.type() == CV_32FC3 && mask.type() == CV_8UC1 && depth.type() == CV_32FC1,
               "AddRegionEquations: expected CV_32FC3 image, CV_8UC1 mask, CV_32FC1 depth");
  UNSEEN_CHECK(image.size() == mask.size() && image.size() == depth.size(),
               "AddRegionEquations: image, mask and depth differ in size");
  const int width = image.cols, height = image.rows;
  if (width < 5 || height < 5) return;
  const bool solve = histograms->learnt();
  if (!solve && !learn) return;

  const int half = options.line_px;
  const int samples = 2 * half;  // at s = k + 0.5, k = -half .. half - 1
  const float origin[3] = {float(in.origin_in_cam.x()), float(in.origin_in_cam.y()),
                           float(in.origin_in_cam.z())};
  const float fx = float(in.camera.fx), fy = float(in.camera.fy);
  const float cx = float(in.camera.cx), cy = float(in.camera.cy);
  std::vector<float> log_fg(samples + 1), log_bg(samples + 1), posterior(samples);
  std::vector<int> bins(samples);
  std::vector<double> log_p(samples + 1);
  RegionCounts c;
  const cv::Mat* occluded = options.skip_occluded_lines && in.occluded_block_px > 0
                                ? in.occluded_blocks
                                : nullptr;
  auto in_occluded_block = [&](float x, float y) {
    const int bx = int(std::floor(x)) / in.occluded_block_px;
    const int by = int(std::floor(y)) / in.occluded_block_px;
    return x >= 0.0f && y >= 0.0f && bx < occluded->cols && by < occluded->rows &&
           occluded->ptr<uint8_t>(by)[bx] != 0;
  };
  for (const ContourSample& cs : SampleContour(mask, options.max_lines)) {
    // The contour lies half a pixel outside the centre of a boundary pixel whose centre is
    // covered; a partly covered one holds it, as far out as its coverage. The line runs
    // inward until it leaves the rendered object and outward until it meets it again (the
    // object's far side or another part of it is no evidence about this contour).
    const float offset =
        in.coverage ? 0.25f * float(in.coverage->ptr<uint8_t>(cs.y)[cs.x]) - 0.5f : 0.5f;
    const float px = cs.x + offset * cs.nx, py = cs.y + offset * cs.ny;
    if (occluded) {
      const float probe = float(options.occluded_probe_px);
      if (in_occluded_block(px, py) ||
          in_occluded_block(px - probe * cs.nx, py - probe * cs.ny)) {
        ++c.occluded;
        continue;
      }
    }
    auto sample_pixel = [&](int k, int* sx, int* sy) {
      const float s = float(k - half) + 0.5f;
      *sx = int(std::lround(px + s * cs.nx));
      *sy = int(std::lround(py + s * cs.ny));
      return *sx >= 0 && *sy >= 0 && *sx < width && *sy < height;
    };
    int first = half, last = half - 1;  // the line's samples [first, last]
    bool clipped = false;
    for (int k = half - 1; k >= 0; --k) {
      int sx, sy;
      if (!sample_pixel(k, &sx, &sy)) {
        clipped = true;
        break;
      }
      if (!mask.ptr<uint8_t>(sy)[sx]) break;
      first = k;
    }
    for (int k = half; k < samples; ++k) {
      int sx, sy;
      if (!sample_pixel(k, &sx, &sy)) {
        clipped = true;
        break;
      }
      // The boundary pixel itself holds the contour: beyond it is outside.
      if (mask.ptr<uint8_t>(sy)[sx] && !(sx == cs.x && sy == cs.y)) break;
      last = k;
    }
    constexpr int kMinSide = 2;
    if (clipped || half - first < kMinSide || last - half + 1 < kMinSide) continue;
    ++c.lines;
    const float* previous = nullptr;
    float largest_step = -1.0f;
    int step_at = 0;  // boundary d between samples d - 1 and d
    for (int k = first; k <= last; ++k) {
      int sx, sy;
      sample_pixel(k, &sx, &sy);
      const float* bgr = image.ptr<float>(sy) + 3 * sx;
      if (previous) {
        const float step = std::abs(bgr[0] - previous[0]) + std::abs(bgr[1] - previous[1]) +
                           std::abs(bgr[2] - previous[2]);
        if (step > largest_step) {
          largest_step = step;
          step_at = k;
        }
      }
      previous = bgr;
      bins[k] = histograms->Bin(bgr);
      posterior[k] = solve ? histograms->Posterior(bins[k]) : 0.5f;
      if (learn) {
        const float s = float(k - half) + 0.5f;
        if (s < -options.foreground_margin_px) histograms->Count(bgr, true);
        if (s > options.background_margin_px) histograms->Count(bgr, false);
      }
    }
    const bool edge_on_contour = largest_step > 0.0f && std::abs(step_at - half) <= 1;
    if (edge_on_contour) ++c.edge_lines;
    if (!solve) continue;
    // Agreement of the pixels away from the contour with the side they are on.
    double contrast = 0.0;
    for (int k = first; k <= last; ++k) {
      const float s = float(k - half) + 0.5f;
      contrast += std::abs(posterior[k] - 0.5f) * 2.0f;
      if (std::abs(s) < 1.0f) continue;
      ++c.pixels;
      if ((s < 0.0f) == (posterior[k] > 0.5f)) ++c.agreeing;
    }
    contrast /= (last - first + 1);
    // log P(d) for the contour between samples d - 1 and d (d = first .. last + 1):
    // foreground before it, background after it. Prefix sums of the two logs.
    log_fg[first] = 0.0f;
    for (int k = first; k <= last; ++k) log_fg[k + 1] = log_fg[k] + histograms->LogForeground(bins[k]);
    log_bg[last + 1] = 0.0f;
    for (int k = last; k >= first; --k) log_bg[k] = log_bg[k + 1] + histograms->LogBackground(bins[k]);
    double best = -1e30;
    int most_likely = first;
    for (int d = first; d <= last + 1; ++d) {
      log_p[d] = double(log_fg[d]) + double(log_bg[d]);
      if (log_p[d] > best) {
        best = log_p[d];
        most_likely = d;
      }
    }
    // The most likely contour past the last sample of a line that ran its whole outer half:
    // the object's colours go on beyond it.
    if (most_likely == last + 1 && last == samples - 1) {
      ++c.overrun;
      if (in.skip_overrun) continue;
    }
    double sum = 0.0, mean = 0.0;
    for (int d = first; d <= last + 1; ++d) {
      const double p = std::exp(log_p[d] - best);
      log_p[d] = p;
      sum += p;
      mean += p * double(d - half);  // the position of boundary d on the line
    }
    mean /= sum;
    double variance = 0.0;
    for (int d = first; d <= last + 1; ++d) {
      const double e = double(d - half) - mean;
      variance += log_p[d] * e * e;
    }
    variance /= sum;
    const double sigma = std::max(std::sqrt(variance), options.min_sigma_px);
    if (sigma > options.max_sigma_px || contrast < options.min_contrast) continue;
    if (options.edge_contradiction_px > 0.0 && edge_on_contour &&
        std::abs(mean) > options.edge_contradiction_px) {
      continue;
    }
    const float z = depth.ptr<float>(cs.y)[cs.x];
    if (!(z > 0.0f)) continue;
    // Flow row with the unit normal as the "gradient", scaled by 1 / sigma: its residual
    // is the contour offset in standard deviations.
    float row[6];
    const float inv_sigma = static_cast<float>(1.0 / sigma);
    FlowRowInCamera(fx, fy, cx, cy, origin, px + in.roi.x0, py + in.roi.y0, z,
                    cs.nx * inv_sigma, cs.ny * inv_sigma, row);
    out->Add(row, static_cast<float>(mean) * inv_sigma, 1.0f);
    ++c.used;
  }
  *counts += c;
}

RegionModality::RegionModality(const RegionModalityOptions& options, int num_cameras)
    : CountingModality("region"), options_(options) {
  residual_model() = options.residual;
  UNSEEN_CHECK(num_cameras >= 1, "RegionModality: {} cameras", num_cameras);
  histograms_.assign(num_cameras, ColorHistograms(options.bins_per_channel));
}

void RegionModality::AddEquations(const ModalityRound& round) {
  UNSEEN_CHECK(round.virtual_image && round.input, "RegionModality: the round has no images");
  UNSEEN_CHECK(round.camera >= 0 && round.camera < static_cast<int>(histograms_.size()),
               "RegionModality: camera {} of {}", round.camera, histograms_.size());
  RegionModalityInput in;
  in.image = round.input;
  in.mask = &round.virtual_image->mask;
  in.rendered_depth = &round.virtual_image->depth;
  in.coverage = &round.virtual_image->coverage;
  in.roi = round.roi;
  in.camera = round.level_camera;
  in.origin_in_cam = round.origin_in_cam;
  in.level = round.level;
  in.occluded_blocks = round.occluded_blocks;
  in.occluded_block_px = round.occluded_block_px;
  in.skip_overrun = options_.skip_overrun_lines && round.without_texture;
  ColorHistograms& h = histograms_[round.camera];
  FlowEquations& out = CameraEquations(round);
  RegionCounts& counts = CameraCounts(round);
  const bool first = !h.learnt() && round.first_frame;
  AddRegionEquations(in, options_, round.learn || first, &h, &out, &counts);
  if (first) {
    // Nothing learnt yet: the given pose teaches the statistics at once, then the lines
    // are judged by them.
    h.Commit(1.0);
    if (h.learnt()) AddRegionEquations(in, options_, false, &h, &out, &counts);
  }
}

void RegionModality::Commit(double rate) {
  for (ColorHistograms& h : histograms_) h.Commit(rate);
}

void RegionModality::DiscardPending() {
  for (ColorHistograms& h : histograms_) h.DiscardPending();
}

void RegionModality::Reset() {
  for (ColorHistograms& h : histograms_) h.Reset();
}

}  // namespace unseen
