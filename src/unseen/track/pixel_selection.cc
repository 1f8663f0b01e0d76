// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/pixel_selection.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "unseen/track/flow_jacobian.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

// Luminance weights in BGR order (ITU-R BT.601).
constexpr float kGreyWeights[3] = {0.114f, 0.587f, 0.299f};

}  // namespace

const char* ToString(ColorMode mode) {
  switch (mode) {
    case ColorMode::kColorGradientRedundancy: return "redundancy";
    case ColorMode::kRawColor: return "raw";
    case ColorMode::kGrey: return "grey";
  }
  return "?";
}

ColorMode ParseColorMode(const std::string& text, const std::string& what) {
  if (text == "redundancy") return ColorMode::kColorGradientRedundancy;
  if (text == "raw") return ColorMode::kRawColor;
  if (text == "grey" || text == "gray") return ColorMode::kGrey;
  ThrowError("{}: unknown colour mode '{}' (redundancy, raw, grey)", what, text);
}

void PixelSelectionOptions::Check() const {
  UNSEEN_CHECK(min_gradient_sq >= 0.0 && std::isfinite(min_gradient_sq),
               "selection.min_gradient_sq {} must be >= 0", min_gradient_sq);
  UNSEEN_CHECK(max_normal_flow_px > 0.0 && std::isfinite(max_normal_flow_px),
               "selection.max_normal_flow_px {} must be > 0", max_normal_flow_px);
  UNSEEN_CHECK(occlusion_min_gradient_sq >= 0.0 && std::isfinite(occlusion_min_gradient_sq),
               "selection.occlusion_min_gradient_sq {} must be >= 0", occlusion_min_gradient_sq);
  UNSEEN_CHECK(occlusion_max_angle_rad > 0.0 && occlusion_max_angle_rad <= M_PI,
               "selection.occlusion_max_angle_rad {} must be in (0, pi]", occlusion_max_angle_rad);
  UNSEEN_CHECK(occlusion_max_magnitude_diff > 0.0 && std::isfinite(occlusion_max_magnitude_diff),
               "selection.occlusion_max_magnitude_diff {} must be > 0",
               occlusion_max_magnitude_diff);
  UNSEEN_CHECK(min_eigen_ratio >= 1.0 && std::isfinite(min_eigen_ratio),
               "selection.min_eigen_ratio {} must be >= 1", min_eigen_ratio);
  UNSEEN_CHECK(block_px >= 2 && block_px <= 256, "selection.block_px {} must be in [2, 256]",
               block_px);
  UNSEEN_CHECK(block_min_gradient >= 1, "selection.block_min_gradient {} must be >= 1",
               block_min_gradient);
  UNSEEN_CHECK(block_min_share_ratio >= 0.0 && block_min_share_ratio <= 1.0,
               "selection.block_min_share_ratio {} must be in [0, 1]", block_min_share_ratio);
  UNSEEN_CHECK(block_min_blocks >= 1, "selection.block_min_blocks {} must be >= 1",
               block_min_blocks);
}

SelectionCounts& SelectionCounts::operator+=(const SelectionCounts& o) {
  candidates += o.candidates;
  rejected_gradient += o.rejected_gradient;
  rejected_input_gradient += o.rejected_input_gradient;
  rejected_direction += o.rejected_direction;
  rejected_magnitude += o.rejected_magnitude;
  rejected_undirected += o.rejected_undirected;
  rejected_normal_flow += o.rejected_normal_flow;
  rejected_block += o.rejected_block;
  occluded_gradient += o.occluded_gradient;
  used += o.used;
  equations += o.equations;
  block_share_sum += o.block_share_sum;
  block_used += o.block_used;
  return *this;
}

double SelectionCounts::RejectionGathering() const {
  if (block_used <= 0 || gradient_pixels() <= 0) return 0.0;
  const double share = double(used) / double(gradient_pixels());
  if (share >= 1.0) return 0.0;
  return std::clamp((BlockShare() - share) / (1.0 - share), 0.0, 1.0);
}

void SelectPixels(const SelectionInput& in, const PixelSelectionOptions& options,
                  FlowEquations* out, SelectionCounts* counts,
                  std::vector<PhotometricSample>* samples, cv::Mat* occluded_blocks) {
  const PreprocessedImage& v = *in.virtual_image;
  const PreprocessedImage& im = *in.input_image;
  const int w = in.roi.width(), h = in.roi.height();
  UNSEEN_CHECK(v.blurred.cols == w && v.blurred.rows == h && v.gx.size() == v.blurred.size() &&
                   im.blurred.size() == v.blurred.size() && in.region->size() == v.blurred.size() &&
                   in.depth->size() == v.blurred.size(),
               "SelectPixels: buffers do not match the region {}x{}", w, h);
  const bool occlusion = options.use_occlusion_rejection;
  UNSEEN_CHECK(!occlusion || im.gx.size() == v.blurred.size(),
               "SelectPixels: occlusion rejection needs the input image's gradients");

  const float tau = options.use_gradient_threshold ? float(options.min_gradient_sq) : 0.0f;
  const float tvmax_sq = float(options.max_normal_flow_px * options.max_normal_flow_px);
  const float tgm = float(options.occlusion_min_gradient_sq);
  const float cos_theta = float(std::cos(options.occlusion_max_angle_rad));
  const float tmd = float(options.occlusion_max_magnitude_diff);
  const float ratio = float(options.min_eigen_ratio);
  const float fx = float(in.camera.fx), fy = float(in.camera.fy);
  const float cx = float(in.camera.cx), cy = float(in.camera.cy);
  const float origin[3] = {float(in.origin_in_cam.x()), float(in.origin_in_cam.y()),
                           float(in.origin_in_cam.z())};
  SelectionCounts c;
  SelectionCounts rim;  // the rim's tallies, not reported
  float row[6];
  // Per block: gradient pixels and those that passed the occlusion tests, rim included
  // (what decides a block's occlusion: a block mostly of rim may be dropped), and the
  // object's own gradient and used pixels (what the counts report).
  const int block = options.block_px;
  const int block_cols = (w + block - 1) / block, block_rows = (h + block - 1) / block;
  std::vector<int> block_gradient(block_cols * block_rows, 0);
  std::vector<int> block_passed(block_cols * block_rows, 0);  // passed (4.13)-(4.15)
  std::vector<int> own_gradient(block_cols * block_rows, 0);
  std::vector<int> own_used(block_cols * block_rows, 0);
  const int first_row = out->size();
  const size_t first_sample = samples ? samples->size() : 0;
  std::vector<int> row_block;  // block of each row appended here
  if (occluded_blocks) {
    occluded_blocks->create(block_rows, block_cols, CV_8UC1);
    occluded_blocks->setTo(0);
  }

  for (int y = 0; y < h; ++y) {
    int* row_gradient = block_gradient.data() + (y / block) * block_cols;
    int* row_passed = block_passed.data() + (y / block) * block_cols;
    int* row_own_gradient = own_gradient.data() + (y / block) * block_cols;
    int* row_own_used = own_used.data() + (y / block) * block_cols;
    const uint8_t* reg = in.region->ptr<uint8_t>(y);
    const float* dep = in.depth->ptr<float>(y);
    const float* vb = v.blurred.ptr<float>(y);
    // Appends `row` as the equation row . twist = b of pixel (x, y), noting its block.
    // `weight`: the channels' weights in the equation, for its PhotometricSample.
    auto add_equation = [&](int x, float b, float inv_grad_norm, const float weight[3]) {
      out->Add(row, b, inv_grad_norm);
      if (samples) {
        PhotometricSample& sample = samples->emplace_back();
        sample.x = float(in.roi.x0 + x);
        sample.y = float(in.roi.y0 + y);
        sample.z = dep[x];
        float value = 0.0f;
        for (int j = 0; j < 3; ++j) {
          sample.weight[j] = weight[j];
          value += weight[j] * vb[3 * x + j];
        }
        sample.virtual_value = value;
      }
      row_block.push_back((y / block) * block_cols + x / block);
      ++c.equations;
    };
    auto count_used = [&](int x) {
      if (reg[x] != kObjectPixel) return;
      ++c.used;
      ++row_own_used[x / block];
    };
    const float* vgx = v.gx.ptr<float>(y);
    const float* vgy = v.gy.ptr<float>(y);
    const float* ib = im.blurred.ptr<float>(y);
    const float* igx = occlusion ? im.gx.ptr<float>(y) : nullptr;
    const float* igy = occlusion ? im.gy.ptr<float>(y) : nullptr;
    const float py = float(in.roi.y0 + y);
    for (int x = 0; x < w; ++x) {
      if (!reg[x]) continue;
      const float z = dep[x];
      if (!(z > 0.0f)) continue;
      // A rim pixel gives rows, and joins its block's occlusion test; the counts, and the
      // confidence that reads them, see the object's own pixels only.
      const bool own = reg[x] == kObjectPixel;
      SelectionCounts& tally = own ? c : rim;
      ++tally.candidates;
      const int k = 3 * x;
      const float gx[3] = {vgx[k], vgx[k + 1], vgx[k + 2]};
      const float gy[3] = {vgy[k], vgy[k + 1], vgy[k + 2]};
      const float it[3] = {ib[k] - vb[k], ib[k + 1] - vb[k + 1], ib[k + 2] - vb[k + 2]};
      float sq[3];
      for (int j = 0; j < 3; ++j) sq[j] = gx[j] * gx[j] + gy[j] * gy[j];

      // (4.8) gradient threshold.
      float a = 0, d = 0, cc = 0;  // C = A^T A (3.6)
      bool gradient_ok;
      switch (options.color_mode) {
        case ColorMode::kColorGradientRedundancy: {
          for (int j = 0; j < 3; ++j) {
            a += gx[j] * gx[j];
            d += gy[j] * gy[j];
            cc += gx[j] * gy[j];
          }
          const float l1 = 0.5f * (a + d) + std::sqrt(0.25f * (a - d) * (a - d) + cc * cc);
          gradient_ok = l1 > tau && l1 > 0.0f;
          break;
        }
        case ColorMode::kGrey: {
          float ggx = 0, ggy = 0;
          for (int j = 0; j < 3; ++j) {
            ggx += kGreyWeights[j] * gx[j];
            ggy += kGreyWeights[j] * gy[j];
          }
          const float s = ggx * ggx + ggy * ggy;
          gradient_ok = s > tau && s > 0.0f;
          break;
        }
        case ColorMode::kRawColor:
        default:
          gradient_ok = (sq[0] > tau && sq[0] > 0) || (sq[1] > tau && sq[1] > 0) ||
                        (sq[2] > tau && sq[2] > 0);
          break;
      }
      if (!gradient_ok) {
        ++tally.rejected_gradient;
        continue;
      }
      ++row_gradient[x / block];
      if (own) ++row_own_gradient[x / block];

      // (4.13)-(4.15) occlusion rejection, per channel.
      if (occlusion) {
        const float hx[3] = {igx[k], igx[k + 1], igx[k + 2]};
        const float hy[3] = {igy[k], igy[k + 1], igy[k + 2]};
        bool input_ok = true, direction_ok = true;
        float mag_v = 0, mag_i = 0;
        for (int j = 0; j < 3; ++j) {
          const float si = hx[j] * hx[j] + hy[j] * hy[j];
          mag_v += sq[j];
          mag_i += si;
          if (sq[j] > tgm) {
            if (si <= tgm) {
              input_ok = false;
            } else if (gx[j] * hx[j] + gy[j] * hy[j] < cos_theta * std::sqrt(sq[j] * si)) {
              direction_ok = false;
            }
          }
        }
        if (!input_ok) {
          ++tally.rejected_input_gradient;
          continue;
        }
        if (!direction_ok) {
          ++tally.rejected_direction;
          continue;
        }
        if (std::abs(std::sqrt(mag_v) - std::sqrt(mag_i)) >= tmd) {
          ++tally.rejected_magnitude;
          continue;
        }
        ++row_passed[x / block];
      }

      const float px = float(in.roi.x0 + x);
      switch (options.color_mode) {
        case ColorMode::kColorGradientRedundancy: {
          const float l1 = 0.5f * (a + d) + std::sqrt(0.25f * (a - d) * (a - d) + cc * cc);
          const float l2 = std::max(a + d - l1, 0.0f);
          if (l1 < ratio * l2) {
            ++tally.rejected_undirected;
            continue;
          }
          const bool by_y = d > a;
          float sgx = 0, sgy = 0, sit = 0;
          float signs[3];
          for (int j = 0; j < 3; ++j) {
            const float s = (by_y ? gy[j] : gx[j]) < 0.0f ? -1.0f : 1.0f;
            signs[j] = s;
            sgx += s * gx[j];
            sgy += s * gy[j];
            sit += s * it[j];
          }
          const float g2 = sgx * sgx + sgy * sgy;
          if (!(g2 > 0.0f) || (options.use_normal_flow_bound && sit * sit >= tvmax_sq * g2)) {
            ++tally.rejected_normal_flow;
            continue;
          }
          FlowRowInCamera(fx, fy, cx, cy, origin, px, py, z, sgx, sgy, row);
          add_equation(x, -sit, 1.0f / std::sqrt(g2), signs);
          count_used(x);
          break;
        }
        case ColorMode::kGrey: {
          float ggx = 0, ggy = 0, git = 0;
          for (int j = 0; j < 3; ++j) {
            ggx += kGreyWeights[j] * gx[j];
            ggy += kGreyWeights[j] * gy[j];
            git += kGreyWeights[j] * it[j];
          }
          const float g2 = ggx * ggx + ggy * ggy;
          if (options.use_normal_flow_bound && git * git >= tvmax_sq * g2) {
            ++tally.rejected_normal_flow;
            continue;
          }
          FlowRowInCamera(fx, fy, cx, cy, origin, px, py, z, ggx, ggy, row);
          add_equation(x, -git, 1.0f / std::sqrt(g2), kGreyWeights);
          count_used(x);
          break;
        }
        case ColorMode::kRawColor: {
          int added = 0;
          bool flow_rejected = false;
          for (int j = 0; j < 3; ++j) {
            if (!(sq[j] > tau && sq[j] > 0.0f)) continue;
            if (options.use_normal_flow_bound && it[j] * it[j] >= tvmax_sq * sq[j]) {
              flow_rejected = true;
              continue;
            }
            FlowRowInCamera(fx, fy, cx, cy, origin, px, py, z, gx[j], gy[j], row);
            float channel[3] = {0.0f, 0.0f, 0.0f};
            channel[j] = 1.0f;
            add_equation(x, -it[j], 1.0f / std::sqrt(sq[j]), channel);
            ++added;
          }
          if (added == 0) {
            if (flow_rejected) ++tally.rejected_normal_flow;
            continue;
          }
          count_used(x);
          break;
        }
      }
    }
  }
  for (size_t b = 0; b < own_gradient.size(); ++b) {
    if (own_gradient[b] < options.block_min_gradient) continue;
    c.block_share_sum += double(own_used[b]) * own_used[b] / own_gradient[b];
    c.block_used += own_used[b];
  }
  if (occlusion && options.block_min_share_ratio > 0.0) {
    // Shares of the occlusion tests alone: a misalignment also fails the normal-flow bound
    // (4.9), in whole blocks along the silhouette, which must stay to bring the pose back.
    std::vector<float> shares;
    for (size_t b = 0; b < block_gradient.size(); ++b) {
      if (block_gradient[b] >= options.block_min_gradient) {
        shares.push_back(float(block_passed[b]) / float(block_gradient[b]));
      }
    }
    if (!shares.empty() && static_cast<int>(shares.size()) >= options.block_min_blocks) {
      const size_t mid = shares.size() / 2;
      std::nth_element(shares.begin(), shares.begin() + mid, shares.end());
      const float min_share = float(options.block_min_share_ratio) * shares[mid];
      std::vector<uint8_t> drop(block_gradient.size(), 0);
      for (size_t b = 0; b < block_gradient.size(); ++b) {
        drop[b] = block_gradient[b] >= options.block_min_gradient &&
                  float(block_passed[b]) < min_share * float(block_gradient[b]);
        if (drop[b]) {
          if (occluded_blocks) occluded_blocks->data[b] = 255;
          c.occluded_gradient += own_gradient[b];
          c.rejected_block += own_used[b];
          c.used -= own_used[b];
        }
      }
      int kept = first_row;
      for (size_t i = 0; i < row_block.size(); ++i) {
        if (drop[row_block[i]]) continue;
        const int from = first_row + static_cast<int>(i);
        if (kept != from) {
          out->rows[kept] = out->rows[from];
          out->rhs[kept] = out->rhs[from];
          out->inv_grad_norm[kept] = out->inv_grad_norm[from];
          if (samples) (*samples)[first_sample + (kept - first_row)] = (*samples)[first_sample + i];
        }
        ++kept;
      }
      c.equations -= out->size() - kept;
      out->rows.resize(kept);
      out->rhs.resize(kept);
      out->inv_grad_norm.resize(kept);
      if (samples) samples->resize(first_sample + (kept - first_row));
    }
  }
  *counts += c;
}

}  // namespace unseen
