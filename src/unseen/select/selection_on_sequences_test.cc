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

Score SelectOver(const std::string& name, int frames) {
  const fs::path dir = fs::path(UNSEEN_SOURCE_DIR) / "../shared/data/sequences" / name;
  Score score;
  if (!fs::is_directory(dir)) return score;
  const Sequence sequence = Sequence::Open(dir.string());
  const int reference = sequence.reference_camera();
  const RigCamera& camera = sequence.rig().cameras[reference];
  InterestFilterBank bank;
  bank.Add(std::make_unique<MotionFilter>(MotionFilterOptions()));
  for (int i = 0; i < std::min(frames, sequence.num_frames()); ++i) {
    const Frame frame = sequence.ReadFrame(i);
    FilterFrame in;
    in.image = frame.images[reference];
    in.camera = camera.intrinsics;
    in.world_from_cam = camera.world_from_cam;
    const cv::Mat interest = bank.Apply(in);
    if (!bank.ready()) continue;
    ++score.frames;
    RegionSelectionOptions options;
    options.rank_by_total_interest = true;
    const RegionSelection s =
        SelectRegion(InterestRegions(interest, options.min_interest), interest, cv::Mat(),
                     cv::Mat(), camera.intrinsics, options);
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

// Motion alone (MOG2 after 8 frames), regions from its closed mask, the largest total
// interest: measured 94 of 143 judged frames on the cube over clutter, 101 of 143 on the
// white zig-zag (the thesis's highest mean interest: 74 of the first 113, and 100). A slowly moving
// textured object's motion mask comes in pieces; block-based motion segmentation is the next step.
// The occluded box is not here: the bar sweeping in front moves more (0 of 143; that needs another
// filter in the bank, e.g. colour).
TEST(SelectionOnSequences, TheMovingObjectIsSelectedBeforeAStaticCamera) {
  for (const char* name : {"cube_clutter_sidelight", "cube_white_zigzag"}) {
    const Score s = SelectOver(name, 150);
    if (s.frames == 0) {
      std::printf("%s not found: skipped\n", name);
      continue;
    }
    std::printf("%s: %d frames judged, %d with a selection, %d of them the object\n", name,
                s.frames, s.selected, s.right);
    EXPECT_GE(s.right, 0.55 * s.frames) << name;
  }
}

}  // namespace
}  // namespace unseen
