// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/render/mipmap.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <mutex>

#include <opencv2/imgproc.hpp>

#include "unseen/util/error.h"

namespace unseen {

namespace {

constexpr int kMaxLevels = 12;
constexpr size_t kCacheSize = 16;  // textures

struct Entry {
  const void* data = nullptr;
  int rows = 0, cols = 0;
  size_t step = 0;
  uint64_t fingerprint = 0;
  uint64_t last_use = 0;
  std::shared_ptr<const std::vector<cv::Mat>> reduced;  // levels 1, 2, ...
};

struct Cache {
  std::mutex mutex;
  std::vector<Entry> entries;
  uint64_t clock = 0;
};

Cache& TheCache() {
  static Cache cache;
  return cache;
}

// FNV-1a over the bytes of 64 texels spread over the image (and its size).
uint64_t Fingerprint(const cv::Mat& t) {
  uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const void* p, size_t n) {
    const unsigned char* b = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  };
  const int n = 8;
  for (int j = 0; j < n; ++j) {
    const int y = static_cast<int>((int64_t(2 * j + 1) * t.rows) / (2 * n));
    for (int i = 0; i < n; ++i) {
      // Spread columns differently on each row so that the samples are not aligned.
      const int x = static_cast<int>((int64_t(2 * i + 1) * t.cols + j * 7) / (2 * n)) % t.cols;
      mix(t.ptr<float>(y) + 3 * x, 3 * sizeof(float));
    }
  }
  return h;
}

// Levels 1, 2, ... (the cache does not keep the texture itself alive).
std::shared_ptr<const std::vector<cv::Mat>> BuildReduced(const cv::Mat& texture) {
  auto reduced = std::make_shared<std::vector<cv::Mat>>();
  cv::Mat prev = texture;
  while (static_cast<int>(reduced->size()) + 1 < kMaxLevels && (prev.cols > 1 || prev.rows > 1)) {
    cv::Mat next;
    cv::resize(prev, next, cv::Size((prev.cols + 1) / 2, (prev.rows + 1) / 2), 0, 0,
               cv::INTER_AREA);
    reduced->push_back(next);
    prev = next;
  }
  return reduced;
}

std::vector<cv::Mat> WithTexture(const cv::Mat& texture, const std::vector<cv::Mat>& reduced) {
  std::vector<cv::Mat> levels;
  levels.reserve(reduced.size() + 1);
  levels.push_back(texture);
  levels.insert(levels.end(), reduced.begin(), reduced.end());
  return levels;
}

}  // namespace

std::vector<cv::Mat> MipmapLevels(const cv::Mat& texture) {
  UNSEEN_CHECK(!texture.empty() && texture.type() == CV_32FC3,
               "MipmapLevels: texture must be a non-empty CV_32FC3 image (type {}, {}x{})",
               texture.type(), texture.cols, texture.rows);
  const uint64_t fingerprint = Fingerprint(texture);
  Cache& cache = TheCache();
  {
    std::lock_guard<std::mutex> lock(cache.mutex);
    for (Entry& e : cache.entries) {
      if (e.data == texture.data && e.rows == texture.rows && e.cols == texture.cols &&
          e.step == texture.step[0] && e.fingerprint == fingerprint) {
        e.last_use = ++cache.clock;
        return WithTexture(texture, *e.reduced);
      }
    }
  }
  // Built outside the lock; a concurrent build of the same texture only wastes time.
  Entry entry;
  entry.data = texture.data;
  entry.rows = texture.rows;
  entry.cols = texture.cols;
  entry.step = texture.step[0];
  entry.fingerprint = fingerprint;
  entry.reduced = BuildReduced(texture);
  std::lock_guard<std::mutex> lock(cache.mutex);
  entry.last_use = ++cache.clock;
  // Drop entries for the same buffer (stale content) and the least recently used.
  std::erase_if(cache.entries, [&](const Entry& e) {
    return e.data == entry.data && e.rows == entry.rows && e.cols == entry.cols;
  });
  if (cache.entries.size() >= kCacheSize) {
    cache.entries.erase(std::min_element(
        cache.entries.begin(), cache.entries.end(),
        [](const Entry& a, const Entry& b) { return a.last_use < b.last_use; }));
  }
  cache.entries.push_back(entry);
  return WithTexture(texture, *entry.reduced);
}

void ClearMipmapCache() {
  Cache& cache = TheCache();
  std::lock_guard<std::mutex> lock(cache.mutex);
  cache.entries.clear();
}

int MipmapLevelFor(double texels_per_pixel, int num_levels) {
  if (!(texels_per_pixel > 1.0) || num_levels <= 1) return 0;
  const int level = static_cast<int>(std::floor(0.5 * std::log2(texels_per_pixel)));
  return std::clamp(level, 0, num_levels - 1);
}

}  // namespace unseen
