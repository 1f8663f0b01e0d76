// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The interest filters and the region selection on the development sequences with a
// moving object before a static camera: the selected region must be the object (its
// box overlapping the true visible mask's box) once the background is learnt.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "unseen/io/sequence.h"
#include "unseen/select/interest_filter.h"
#include "unseen/select/interest_filter_bank.h"
#include "unseen/select/motion_segmentation.h"
#include "unseen/select/region_selection.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

// Intersection over union of two boxes.
double BoxIou(const PixelRect& a, const PixelRect& b) {
  const PixelRect both = a.Intersect(b);
  const double inter = both.empty() ? 0.0 : double(both.width()) * both.height();
  return inter / (double(a.width()) * a.height() + double(b.width()) * b.height() - inter);
}

struct Score {
  int frames = 0, selected = 0, right = 0;
};

// Regions from the interest map's closed connected parts, or from motion segmentation.
enum class Regions { kInterestParts, kMotionSegmentation };

Score SelectOver(const std::string& name, int frames, Regions regions) {
  const fs::path dir = fs::path(UNSEEN_SOURCE_DIR) / "../shared/data/sequences" / name;
  Score score;
  if (!fs::is_directory(dir)) return score;
  const Sequence sequence = Sequence::Open(dir.string());
  const int reference = sequence.reference_camera();
  const RigCamera& camera = sequence.rig().cameras[reference];
  InterestFilterBank bank;
  bank.Add(std::make_unique<MotionFilter>(MotionFilterOptions()));
  MotionSegmenter segmenter;
  for (int i = 0; i < std::min(frames, sequence.num_frames()); ++i) {
    const Frame frame = sequence.ReadFrame(i);
    FilterFrame in;
    in.image = frame.images[reference];
    in.camera = camera.intrinsics;
    in.world_from_cam = camera.world_from_cam;
    const cv::Mat interest = bank.Apply(in);
    const cv::Mat segments = segmenter.Segment(in.image, interest);
    if (!bank.ready()) continue;
    ++score.frames;
    RegionSelectionOptions options;
    options.rank_by_total_interest = true;
    // A motion region holds the object's whole area, the background model flags mostly its
    // edges (the setting of `track --init auto`).
    if (regions == Regions::kMotionSegmentation) {
      options.min_interest_share = 0.05;
      options.min_mean_interest = 0.05;
    }
    const RegionSelection s = SelectRegion(
        regions == Regions::kInterestParts ? InterestRegions(interest, options.min_interest)
                                           : segments,
        interest, cv::Mat(), cv::Mat(), camera.intrinsics, options);
    if (!s.found()) continue;
    ++score.selected;
    const cv::Mat mask = cv::imread(
        (dir / camera.name / "mask_visib" / fmt::format("{:06d}_000000.png", frame.frame_id))
            .string(),
        cv::IMREAD_GRAYSCALE);
    const cv::Rect truth = cv::boundingRect(mask);
    if (BoxIou(s.object().box,
               PixelRect{truth.x, truth.y, truth.x + truth.width, truth.y + truth.height}) >= 0.5) {
      ++score.right;
    }
  }
  return score;
}

// Motion alone (MOG2 after 8 frames), the candidate of largest total interest. Regions from
// the interest map's closed connected parts: measured 94 of 143 judged frames on the cube
// over clutter, 101 of 143 on the white zig-zag (the thesis's highest mean interest: 74 of
// the first 113, and 100): a slowly moving textured object's motion mask comes in pieces.
// Regions from the block-based motion segmentation (thesis 2.2.1): 132 and 131 of 143.
// The occluded box is not here: the bar sweeping in front moves more (0 of 143; that needs
// another filter in the bank, e.g. colour).
TEST(SelectionOnSequences, TheMovingObjectIsSelectedBeforeAStaticCamera) {
  for (const char* name : {"cube_clutter_sidelight", "cube_white_zigzag"}) {
    const Score s = SelectOver(name, 150, Regions::kInterestParts);
    const Score m = SelectOver(name, 150, Regions::kMotionSegmentation);
    if (s.frames == 0) {
      std::printf("%s not found: skipped\n", name);
      continue;
    }
    std::printf("%s: %d frames judged, %d with a selection, %d of them the object\n", name,
                s.frames, s.selected, s.right);
    EXPECT_GE(s.right, 0.55 * s.frames) << name;
    std::printf(
        "%s, regions by motion segmentation: %d frames judged, %d with a selection, %d "
        "of them the object\n",
        name, m.frames, m.selected, m.right);
    EXPECT_GE(m.right, 0.85 * m.frames) << name;
  }
}

}  // namespace
}  // namespace unseen
