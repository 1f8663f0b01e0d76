// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/synth/clutter.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "unseen/util/error.h"

namespace unseen {

namespace {

// Uniform helpers over one generator so the sequence of draws (and so the image) is fixed.
class Draw {
 public:
  explicit Draw(uint64_t seed) {
    std::seed_seq seq{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32),
                      0x636c7574u /* "clut" */};
    rng_.seed(seq);
  }
  // Uniform in [lo, hi). Uses the raw 32-bit output so the result does not depend on the
  // standard library's distribution implementation.
  double Uniform(double lo, double hi) {
    return lo + (hi - lo) * (static_cast<double>(rng_()) / 4294967296.0);
  }
  int Int(int lo, int hi) {  // [lo, hi]
    return std::min(hi, lo + static_cast<int>(Uniform(0.0, hi - lo + 1.0)));
  }
  bool Chance(double p) { return Uniform(0.0, 1.0) < p; }
  cv::Scalar Colour(double min_v = 20, double max_v = 235) {
    // Mostly muted colours with some saturated ones, as in an office or a lab.
    const double v = Uniform(min_v, max_v);
    const double sat = Chance(0.3) ? Uniform(0.5, 1.0) : Uniform(0.0, 0.35);
    cv::Scalar c;
    for (int i = 0; i < 3; ++i) c[i] = std::clamp(v * (1.0 - sat * Uniform(0.0, 1.0)), 0.0, 255.0);
    return c;
  }

 private:
  std::mt19937 rng_;
};

void DrawText(cv::Mat& img, Draw& d, cv::Point at, double scale, const cv::Scalar& colour) {
  static const char kChars[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789 -";
  std::string text;
  const int n = d.Int(3, 10);
  for (int i = 0; i < n; ++i) text += kChars[d.Int(0, sizeof(kChars) - 2)];
  const int fonts[] = {cv::FONT_HERSHEY_SIMPLEX, cv::FONT_HERSHEY_DUPLEX, cv::FONT_HERSHEY_COMPLEX,
                       cv::FONT_HERSHEY_TRIPLEX};
  cv::putText(img, text, at, fonts[d.Int(0, 3)], scale, colour,
              std::max(1, static_cast<int>(scale * 2)), cv::LINE_AA);
}

}  // namespace

cv::Mat MakeClutterImage(int width, int height, uint64_t seed) {
  UNSEEN_CHECK(width >= 16 && height >= 16, "clutter image size {}x{} must be at least 16x16",
               width, height);
  Draw d(seed);
  const double s = std::sqrt(static_cast<double>(width) * height) / 1000.0;  // scale of things
  cv::Mat img(height, width, CV_8UC3);

  // A wall lit from one side above a darker floor.
  const cv::Scalar wall = d.Colour(120, 220);
  const cv::Scalar floor_c = d.Colour(40, 120);
  const int horizon = static_cast<int>(height * d.Uniform(0.6, 0.8));
  const double light_x = d.Uniform(0.0, 1.0);
  for (int y = 0; y < height; ++y) {
    cv::Vec3b* row = img.ptr<cv::Vec3b>(y);
    const cv::Scalar& base = y < horizon ? wall : floor_c;
    for (int x = 0; x < width; ++x) {
      const double lit = 0.75 + 0.35 * std::exp(-std::pow((x / double(width) - light_x) * 2.5, 2));
      for (int c = 0; c < 3; ++c) row[x][c] = cv::saturate_cast<uchar>(base[c] * lit);
    }
  }

  // Large furniture: cupboards and shelves with edges and handles.
  const int num_large = d.Int(6, 10);
  for (int i = 0; i < num_large; ++i) {
    const int w = static_cast<int>(d.Uniform(0.08, 0.25) * width);
    const int h = static_cast<int>(d.Uniform(0.2, 0.7) * height);
    const int x = d.Int(-w / 2, width - w / 2);
    const int y = std::max(0, horizon - h + d.Int(-20, 40));
    const cv::Scalar c = d.Colour(30, 200);
    cv::rectangle(img, cv::Rect(x, y, w, h), c, cv::FILLED);
    cv::rectangle(img, cv::Rect(x, y, w, h), c * 0.5, std::max(1, int(3 * s)));
    const int shelves = d.Int(1, 5);
    for (int k = 1; k <= shelves; ++k) {
      const int sy = y + k * h / (shelves + 1);
      cv::line(img, {x, sy}, {x + w, sy}, c * 0.6, std::max(1, int(4 * s)));
      // Things on the shelf.
      for (int j = 0; j < d.Int(1, 6); ++j) {
        const int bw = static_cast<int>(d.Uniform(0.1, 0.3) * w);
        const int bh = static_cast<int>(d.Uniform(0.3, 0.9) * h / (shelves + 1));
        const int bx = x + d.Int(0, std::max(1, w - bw));
        cv::rectangle(img, cv::Rect(bx, sy - bh, bw, bh), d.Colour(), cv::FILLED);
      }
    }
  }

  // Boxes, posters with text, round things.
  const int num_items = static_cast<int>(100 * s * s) + 30;
  for (int i = 0; i < num_items; ++i) {
    const int kind = d.Int(0, 9);
    const cv::Point p(d.Int(0, width - 1), d.Int(0, height - 1));
    const double size = d.Uniform(8, 90) * s;
    const cv::Scalar c = d.Colour();
    switch (kind) {
      case 0:
      case 1:
      case 2: {
        const cv::Rect r(p.x, p.y, static_cast<int>(size * d.Uniform(0.5, 2.0)),
                         static_cast<int>(size * d.Uniform(0.5, 2.0)));
        cv::rectangle(img, r, c, cv::FILLED);
        if (d.Chance(0.25)) {
          DrawText(img, d, {r.x + 2, r.y + r.height / 2}, d.Uniform(0.3, 0.8) * s * 2,
                   d.Colour(0, 255));
        }
        break;
      }
      case 3:
      case 4:
        cv::ellipse(img, p,
                    cv::Size(static_cast<int>(size), static_cast<int>(size * d.Uniform(0.4, 1.0))),
                    d.Uniform(0, 180), 0, 360, c, cv::FILLED, cv::LINE_AA);
        break;
      case 5:
      case 6: {  // cables
        std::vector<cv::Point> pts{p};
        for (int k = 0; k < d.Int(3, 8); ++k) {
          pts.emplace_back(pts.back().x + d.Int(-int(60 * s), int(60 * s)),
                           pts.back().y + d.Int(-int(40 * s), int(40 * s)));
        }
        cv::polylines(img, pts, false, c, std::max(1, int(d.Uniform(1, 5) * s)), cv::LINE_AA);
        break;
      }
      case 7:
        DrawText(img, d, p, d.Uniform(0.4, 1.2) * s * 2, c);
        break;
      default: {  // striped or checked panel
        const int w = static_cast<int>(size * 1.5), h = static_cast<int>(size);
        const int step = std::max(2, static_cast<int>(d.Uniform(3, 12) * s));
        const cv::Scalar c2 = d.Colour();
        for (int k = 0; k * step < w; ++k) {
          cv::rectangle(img, cv::Rect(p.x + k * step, p.y, step, h), k % 2 ? c : c2, cv::FILLED);
        }
        break;
      }
    }
  }

  // Fine texture (wood/fabric-like grain) and a soft camera blur.
  cv::Mat grain(height, width, CV_32FC1);
  for (int y = 0; y < height; ++y) {
    float* row = grain.ptr<float>(y);
    for (int x = 0; x < width; ++x) row[x] = static_cast<float>(d.Uniform(-1.0, 1.0));
  }
  cv::GaussianBlur(grain, grain, cv::Size(0, 0), 1.2);
  cv::Mat out;
  img.convertTo(out, CV_32FC3, 1.0 / 255.0);
  cv::GaussianBlur(out, out, cv::Size(0, 0), 0.7);
  for (int y = 0; y < height; ++y) {
    cv::Vec3f* row = out.ptr<cv::Vec3f>(y);
    const float* g = grain.ptr<float>(y);
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < 3; ++c)
        row[x][c] = std::clamp(row[x][c] * (1.0f + 0.12f * g[x]), 0.0f, 1.0f);
    }
  }
  return out;
}

}  // namespace unseen
