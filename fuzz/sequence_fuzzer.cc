// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Sequence::Open (io/sequence.h) on a sequence folder built from the input, a bundle
// (fuzz_support.h): sequence.json first (left out when empty, which makes a plain BOP scene),
// then the other files by relative path, e.g. "==> cam0/scene_camera.json <==". Every folder
// that gets a scene_camera.json also gets rgb/ with four 8x6 images, frames 0 to 3. An
// opened sequence gives a valid rig, ground truth poses and its first frame.
#include <opencv2/imgcodecs.hpp>

#include "fuzz/fuzz_support.h"
#include "unseen/io/sequence.h"

namespace {

// Four frames, 000000.png to 000003.png, linked as rgb/ into every camera folder.
const unseen::fuzz::Scratch& Images() {
  static const unseen::fuzz::Scratch scratch("sequence_images");
  static const bool written = [] {
    for (int i = 0; i < 4; ++i) {
      cv::imwrite((scratch.dir() / fmt::format("{:06d}.png", i)).string(),
                  cv::Mat(6, 8, CV_8UC3, cv::Scalar(50 * i, 90, 200)));
    }
    return true;
  }();
  (void)written;
  return scratch;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace unseen;
  namespace fs = std::filesystem;
  fuzz::Init();
  const fs::path images = Images().dir();
  static const fuzz::Scratch scratch("sequence");
  const auto files = fuzz::SplitBundle(fuzz::AsText(data, size), "sequence.json");
  if (!files) return 0;
  std::vector<fuzz::BundleFile> written;
  for (const fuzz::BundleFile& file : *files) {
    if (file.name != "sequence.json" || !file.bytes.empty()) written.push_back(file);
  }
  scratch.Reset();
  if (!scratch.WriteBundle(written)) return 0;
  // After every file is written, so that none is written through the link.
  for (const fuzz::BundleFile& file : written) {
    const fs::path camera_dir = (scratch.dir() / file.name).parent_path();
    if (fs::path(file.name).filename() == "scene_camera.json" && !fs::exists(camera_dir / "rgb")) {
      fs::create_directory_symlink(images, camera_dir / "rgb");
    }
  }
  const std::string dir = scratch.dir().string();
  fuzz::ExpectReaderContract("Sequence::Open", dir, [&] {
    const Sequence sequence = Sequence::Open(dir);
    try {
      sequence.rig().Check();
    } catch (const Error& e) {
      fuzz::Fail(std::string("Sequence::Open gave a rig that fails its check: ") + e.what());
    }
    UNSEEN_FUZZ_EXPECT(sequence.num_frames() > 0 && sequence.fps() > 0, "{} frames at {} fps",
                       sequence.num_frames(), sequence.fps());
    for (int i = 0; i < sequence.num_frames(); ++i) {
      for (int c = 0; c < static_cast<int>(sequence.rig().cameras.size()); ++c) {
        const std::optional<Rigid3d> pose = sequence.GroundTruthFromCamera(i, c);
        UNSEEN_FUZZ_EXPECT(!pose || pose->IsValid(), "frame {} camera {}: {}", i, c,
                           pose->ToString());
      }
    }
    const Frame frame = sequence.ReadFrame(0);
    UNSEEN_FUZZ_EXPECT(frame.images.size() == sequence.rig().cameras.size(),
                       "{} images for {} cameras", frame.images.size(),
                       sequence.rig().cameras.size());
  });
  return 0;
}
