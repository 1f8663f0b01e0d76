// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/virtual_image.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <opencv2/imgproc.hpp>

#include "unseen/image/filters.h"
#include "unseen/util/timer.h"

namespace unseen {

namespace {

// PreprocessOptions::background_band_px, over `area` (the rendered rectangle grown by the
// band and the blur's reach): `near` is the mask dilated by the band; `weighted` holds the
// input's pixels beyond the band with weight 1 and the rest with 0, blurred with their
// weight (BGR * weight, weight), the normalized convolution At() divides out.
struct BandBackground {
  BandBackground(const cv::Mat& input_roi, const cv::Mat& mask, const cv::Rect& rendered,
                 const PreprocessOptions& options) {
    const int band = options.background_band_px;
    // (GaussianBlur reaches 4 sigma: the area keeps what the whole region would give.)
    const int reach = band + static_cast<int>(std::ceil(4.0 * options.background_sigma_px)) + 1;
    area = cv::Rect(rendered.x - reach, rendered.y - reach, rendered.width + 2 * reach,
                    rendered.height + 2 * reach) &
           cv::Rect(0, 0, input_roi.cols, input_roi.rows);
    cv::dilate(mask(area), near,
               cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * band + 1, 2 * band + 1)),
               cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
    weighted.create(area.size(), CV_32FC4);
    for (int y = 0; y < area.height; ++y) {
      const float* in = input_roi.ptr<float>(area.y + y) + 3 * area.x;
      const uint8_t* n = near.ptr<uint8_t>(y);
      float* out = weighted.ptr<float>(y);
      for (int x = 0; x < area.width; ++x) {
        const float w = n[x] ? 0.0f : 1.0f;
        for (int k = 0; k < 3; ++k) out[4 * x + k] = w * in[3 * x + k];
        out[4 * x + 3] = w;
      }
    }
    cv::GaussianBlur(weighted, weighted, cv::Size(), options.background_sigma_px);
  }
  // The background at pixel (x, y) of the region (inside `area`), or the input's own pixel
  // where no input beyond the band lies within reach.
  void At(const cv::Mat& input_roi, int x, int y, float* bgr) const {
    const float* b = weighted.ptr<float>(y - area.y) + 4 * (x - area.x);
    const float* in = input_roi.ptr<float>(y) + 3 * x;
    for (int k = 0; k < 3; ++k) bgr[k] = b[3] > 1e-3f ? b[k] / b[3] : in[k];
  }
  // The virtual image's outside within the band shows the background.
  void Paste(const cv::Mat& input_roi, VirtualImage* out) const {
    for (int y = 0; y < area.height; ++y) {
      const uint8_t* m = out->mask.ptr<uint8_t>(area.y + y) + area.x;
      const uint8_t* n = near.ptr<uint8_t>(y);
      float* o = out->composite.ptr<float>(area.y + y);
      for (int x = 0; x < area.width; ++x) {
        if (!m[x] && n[x]) At(input_roi, area.x + x, area.y + y, o + 3 * (area.x + x));
      }
    }
  }
  cv::Rect area;
  cv::Mat near, weighted;
};

// The fully covered pixels of `inside` (weight 1; all else 0) of the input (with the
// weights as a fourth channel) and of the composite, low-passed as LowPassDown would the
// whole-region images, but area-down-sampled by `factor` straight from the covered pixels
// (a pixel of the image padded to a multiple of `factor`, border replicated, counts in the
// block of the border pixel it copies): the whole-region images are never built.
void CoveredLowPass(const cv::Mat& input_roi, const VirtualImage& w, const cv::Rect& inside,
                    double sigma_px, int factor, cv::Mat* real_low, cv::Mat* model_low) {
  const int width = w.composite.cols, height = w.composite.rows;
  const int small_cols = (width + factor - 1) / factor, small_rows = (height + factor - 1) / factor;
  const int pad_cols = small_cols * factor - width, pad_rows = small_rows * factor - height;
  cv::Mat real(small_rows, small_cols, CV_32FC4, cv::Scalar::all(0.0)),
      model(small_rows, small_cols, CV_32FC3, cv::Scalar::all(0.0));
  const float per_pixel = 1.0f / float(factor * factor);  // a power of two: exact
  for (int y = inside.y; y < inside.y + inside.height; ++y) {
    const uint8_t* cov = w.coverage.ptr<uint8_t>(y);
    const float* in = input_roi.ptr<float>(y);
    const float* co = w.composite.ptr<float>(y);
    float* r = real.ptr<float>(y / factor);
    float* m = model.ptr<float>(y / factor);
    const float row_weight = (y == height - 1 ? float(1 + pad_rows) : 1.0f) * per_pixel;
    for (int x = inside.x; x < inside.x + inside.width; ++x) {
      if (cov[x] != 4) continue;
      const float weight = x == width - 1 ? float(1 + pad_cols) * row_weight : row_weight;
      const int s = x / factor;
      for (int k = 0; k < 3; ++k) {
        r[4 * s + k] += weight * in[3 * x + k];
        m[3 * s + k] += weight * co[3 * x + k];
      }
      r[4 * s + 3] += weight;  // the support: share of fully covered pixels
    }
  }
  *real_low = BlurDownsampled(real, sigma_px, factor);
  *model_low = BlurDownsampled(model, sigma_px, factor);
}

}  // namespace

void TransferShading(const cv::Mat& input_roi, const PreprocessOptions& options, int level,
                     const cv::Rect& rendered, VirtualImage* out) {
  VirtualImage& w = *out;
  const cv::Rect inside = rendered & cv::Rect(0, 0, w.composite.cols, w.composite.rows);
  // Low-pass of input and render over the fully covered pixels only (so the background
  // does not leak in); their ratio is the shading the model lacks. The ratio is formed at
  // the low-pass's coarse scale and only it is up-sampled.
  // Outside `rendered` nothing is covered: zero weight there.
  const double sigma = options.ShadingSigmaAtLevel(level);
  const int factor = LowPassFactor(w.composite.size(), sigma);
  cv::Mat real_low, model_low;
  CoveredLowPass(input_roi, w, inside, sigma, factor, &real_low, &model_low);
  cv::Mat gain_low(real_low.size(), CV_32FC3);
  for (int y = 0; y < gain_low.rows; ++y) {
    const float* r = real_low.ptr<float>(y);
    const float* m = model_low.ptr<float>(y);
    float* g = gain_low.ptr<float>(y);
    for (int x = 0; x < gain_low.cols; ++x) {
      const float support = r[4 * x + 3];
      for (int k = 0; k < 3; ++k) {
        const float den = m[3 * x + k];
        g[3 * x + k] = support >= 0.05f && den > 0.01f * support
                           ? std::clamp(r[4 * x + k] / den, 0.2f, 5.0f)
                           : 1.0f;
      }
    }
  }
  const cv::Mat gain = LowPassUp(gain_low, w.composite.size(), factor);
  for (int y = inside.y; y < inside.y + inside.height; ++y) {
    const uint8_t* cov = w.coverage.ptr<uint8_t>(y);
    const float* g = gain.ptr<float>(y);
    float* out = w.composite.ptr<float>(y);
    for (int x = inside.x; x < inside.x + inside.width; ++x) {
      if (!cov[x]) continue;
      for (int k = 0; k < 3; ++k) out[3 * x + k] *= g[3 * x + k];
    }
  }
}

bool ComposeVirtualImage(const Mesh& model, const PinholeCamera& camera,
                         const Rigid3d& cam_from_obj, const PixelRect& roi,
                         const PixelRect& render_rect, const cv::Mat& input_roi, bool supersample,
                         const PreprocessOptions& options, int level, ThreadPool* pool,
                         VirtualImage* out, double* render_ms, double* compose_ms) {
  VirtualImage& w = *out;
  RenderOptions render_options;
  render_options.pool = pool;
  Timer timer;
  const int width = roi.width(), height = roi.height();
  const PixelRect rr = render_rect.empty() ? roi : render_rect;
  const int ox = rr.x0 - roi.x0, oy = rr.y0 - roi.y0;
  const int rw = rr.width(), rh = rr.height();
  if (!supersample) {
    Render(model, camera, cam_from_obj, rr, render_options, &w.render);
    *render_ms += timer.ElapsedMilliseconds();
    if (w.render.mask.rows != rh || w.render.mask.cols != rw) return false;
    // Virtual image = input with the render pasted over it (3.1 step 2).
    timer.Restart();
    const cv::Rect sub(ox, oy, rw, rh);
    input_roi.copyTo(w.composite);
    w.render.color.copyTo(w.composite(sub), w.render.mask);
    w.mask.create(height, width, CV_8UC1);
    w.mask.setTo(0);
    w.render.mask.copyTo(w.mask(sub));
    w.depth.create(height, width, CV_32FC1);
    w.depth.setTo(0.0f);
    w.render.depth.copyTo(w.depth(sub));
    w.coverage.create(height, width, CV_8UC1);
    w.coverage.setTo(0);
    w.coverage.setTo(4, w.mask);
    if (options.shading_transfer) TransferShading(input_roi, options, level, sub, &w);
    if (options.background_band_px > 0) {
      BandBackground(input_roi, w.mask, sub, options).Paste(input_roi, &w);
    }
    *compose_ms += timer.ElapsedMilliseconds();
    return true;
  }
  const PinholeCamera fine = camera.Scaled(0.5);
  const PixelRect fine_roi{2 * rr.x0, 2 * rr.y0, 2 * rr.x1, 2 * rr.y1};
  // Each 2x2 block becomes one pixel below: inside a triangle, one shading of the block.
  render_options.shade_quads = true;
  Render(model, fine, cam_from_obj, fine_roi, render_options, &w.render);
  *render_ms += timer.ElapsedMilliseconds();
  if (w.render.mask.rows != 2 * rh || w.render.mask.cols != 2 * rw) return false;

  // Area-average the 2x2 samples: premultiplied colour, coverage, mean depth of the
  // covered samples. Where coverage is partial, the part not covered shows the background
  // estimated from the neighbouring uncovered pixels of the input (at the true pose the
  // input's own pixel there already mixes in the object, which would bias the silhouette).
  timer.Restart();
  w.composite.create(height, width, CV_32FC3);
  w.mask.create(height, width, CV_8UC1);
  w.depth.create(height, width, CV_32FC1);
  w.coverage.create(height, width, CV_8UC1);
  for (int y = 0; y < height; ++y) {
    const float* in = input_roi.ptr<float>(y);
    float* out = w.composite.ptr<float>(y);
    uint8_t* mask = w.mask.ptr<uint8_t>(y);
    uint8_t* cov = w.coverage.ptr<uint8_t>(y);
    float* depth = w.depth.ptr<float>(y);
    const bool row_rendered = y >= oy && y < oy + rh;
    const int x_begin = row_rendered ? ox : width, x_end = row_rendered ? ox + rw : width;
    // Outside the rendered rectangle: no coverage, the input shows.
    for (int x = 0; x < width; ++x) {
      if (x >= x_begin && x < x_end) continue;
      cov[x] = 0;
      mask[x] = 0;
      depth[x] = 0.0f;
      for (int k = 0; k < 3; ++k) out[3 * x + k] = in[3 * x + k];
    }
    if (!row_rendered) continue;
    const int ry = y - oy;
    const uint8_t* m0 = w.render.mask.ptr<uint8_t>(2 * ry);
    const uint8_t* m1 = w.render.mask.ptr<uint8_t>(2 * ry + 1);
    const float* d0 = w.render.depth.ptr<float>(2 * ry);
    const float* d1 = w.render.depth.ptr<float>(2 * ry + 1);
    const float* c0 = w.render.color.ptr<float>(2 * ry);
    const float* c1 = w.render.color.ptr<float>(2 * ry + 1);
    for (int x = x_begin; x < x_end; ++x) {
      const int a = 2 * (x - ox), b = a + 1;
      const int n = (m0[a] != 0) + (m0[b] != 0) + (m1[a] != 0) + (m1[b] != 0);
      cov[x] = static_cast<uint8_t>(n);
      mask[x] = n ? 255 : 0;
      if (n == 0) {
        depth[x] = 0.0f;
        for (int k = 0; k < 3; ++k) out[3 * x + k] = in[3 * x + k];
        continue;
      }
      depth[x] = (d0[a] + d0[b] + d1[a] + d1[b]) / float(n);
      for (int k = 0; k < 3; ++k) {
        out[3 * x + k] = 0.25f * (c0[3 * a + k] + c0[3 * b + k] + c1[3 * a + k] + c1[3 * b + k]);
      }
    }
  }
  const cv::Rect rendered(ox, oy, rw, rh);
  if (options.shading_transfer) TransferShading(input_roi, options, level, rendered, &w);
  const float gamma = static_cast<float>(options.silhouette_gamma);
  // The uncovered part of a silhouette pixel: the background estimate beyond the band, or
  // (without a band) the mean of the pixel's uncovered neighbours in the input.
  std::optional<BandBackground> band;
  if (options.background_band_px > 0) band.emplace(input_roi, w.mask, rendered, options);
  for (int y = oy; y < oy + rh; ++y) {  // partly covered pixels lie inside the render
    const uint8_t* cov = w.coverage.ptr<uint8_t>(y);
    float* out = w.composite.ptr<float>(y);
    for (int x = ox; x < ox + rw; ++x) {
      const int n = cov[x];
      if (n == 0 || n == 4) continue;
      const float* in = input_roi.ptr<float>(y);
      float back[3] = {in[3 * x], in[3 * x + 1], in[3 * x + 2]};
      if (band) {
        band->At(input_roi, x, y, back);
      } else {
        float sum[3] = {0, 0, 0};
        int count = 0;
        for (int dy = -1; dy <= 1; ++dy) {
          const int yy = y + dy;
          if (yy < 0 || yy >= height) continue;
          const uint8_t* cr = w.coverage.ptr<uint8_t>(yy);
          const float* ir = input_roi.ptr<float>(yy);
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx;
            if (xx < 0 || xx >= width || cr[xx] != 0) continue;
            for (int k = 0; k < 3; ++k) sum[k] += ir[3 * xx + k];
            ++count;
          }
        }
        if (count) {
          for (int k = 0; k < 3; ++k) back[k] = sum[k] / float(count);
        }
      }
      const float alpha = 0.25f * n;
      for (int k = 0; k < 3; ++k) {
        if (gamma == 1.0f) {
          out[3 * x + k] += (1.0f - alpha) * back[k];
        } else {  // mix in linear light, as the camera's pixel integrated it
          const float object = std::max(out[3 * x + k] / alpha, 0.0f);
          const float mixed = alpha * std::pow(object, gamma) +
                              (1.0f - alpha) * std::pow(std::max(back[k], 0.0f), gamma);
          out[3 * x + k] = std::pow(mixed, 1.0f / gamma);
        }
      }
    }
  }
  if (band) band->Paste(input_roi, &w);
  *compose_ms += timer.ElapsedMilliseconds();
  return true;
}

}  // namespace unseen
