// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "tools/unseen/unknown_object.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <vector>

#include "unseen/util/error.h"
#include "unseen/util/files.h"

namespace unseen::cli {

PixelRect ParseRoi(const std::string& text, const std::string& command) {
  std::vector<int> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      v.push_back(std::stoi(item, &used));
      UNSEEN_CHECK(used == item.size(), "trailing characters");
    } catch (const std::exception&) {
      ThrowError("{}: --roi '{}': '{}' is not a whole number of pixels", command, text, item);
    }
  }
  UNSEEN_CHECK(v.size() == 4, "{}: --roi '{}' must be four numbers x,y,w,h", command, text);
  UNSEEN_CHECK(v[2] > 0 && v[3] > 0, "{}: --roi '{}' has no area (w {} h {})", command, text, v[2],
               v[3]);
  return PixelRect{v[0], v[1], v[0] + v[2], v[1] + v[3]};
}

ModellerOptions ModellerOptionsFor(const UnknownObjectArgs& args, const Sequence& sequence,
                                   const std::string& command) {
  // The sequence's natural source (its depth images, else stereo for a pair, else the
  // plane sweep over its cameras), under what the file and --depth say.
  ModellerOptions options;
  options.depth.source =
      NaturalDepthSource(sequence.rig(), sequence.reference_camera(), sequence.has_depth());
  if (!args.model_config.empty()) options = LoadModellerOptions(args.model_config, options);
  if (!args.depth.empty()) {
    try {
      options.depth.source = ParseDepthSourceKind(args.depth);
    } catch (const Error& e) {
      ThrowError("{}: --depth: {}", command, e.what());
    }
  }
  if (options.depth.source == DepthSourceKind::kSensor && !sequence.has_depth()) {
    UNSEEN_CHECK(sequence.rig().size() >= 2,
                 "{}: sequence '{}' has one camera and no depth images: an object without a "
                 "model cannot be modelled from it (give its model with --model, or record "
                 "depth images or a second camera)",
                 command, sequence.path());
    ThrowError(
        "{}: depth source sensor{} but sequence '{}' has no depth images (use "
        "planesweep or stereo with two cameras or more)",
        command, args.depth.empty() ? " (from --model-config)" : " (--depth)", sequence.path());
  }
  return options;
}

ObjectStart LocateUnknownObject(const UnknownObjectArgs& args, const Sequence& sequence, int index,
                                const Frame& frame, const Modeller& modeller,
                                const std::string& command) {
  UNSEEN_CHECK(args.init.empty() || args.init == "gt",
               "{}: --init '{}' for an unknown object must be 'gt' (or use --roi/--mask)", command,
               args.init);
  UNSEEN_CHECK(args.init == "gt" || !args.roi.empty() || !args.mask.empty(),
               "{}: say where the object is: --init gt, --roi x,y,w,h or --mask FILE", command);
  const PinholeCamera& camera = sequence.rig().cameras[modeller.reference()].intrinsics;
  ObjectStart out;
  if (!args.roi.empty()) out.region = ParseRoi(args.roi, command);
  if (!args.mask.empty()) {
    UNSEEN_CHECK(Exists(args.mask), "{}: --mask '{}' does not exist", command, args.mask);
    out.mask = cv::imread(args.mask, cv::IMREAD_GRAYSCALE);
    UNSEEN_CHECK(!out.mask.empty(), "{}: --mask '{}' is not a readable image", command, args.mask);
    UNSEEN_CHECK(out.mask.cols == camera.width && out.mask.rows == camera.height,
                 "{}: --mask '{}' is {}x{}; the reference camera is {}x{}", command, args.mask,
                 out.mask.cols, out.mask.rows, camera.width, camera.height);
    const cv::Rect box = cv::boundingRect(out.mask);
    UNSEEN_CHECK(box.area() > 0, "{}: --mask '{}' marks no pixel", command, args.mask);
    const PixelRect mask_rect{box.x, box.y, box.x + box.width, box.y + box.height};
    out.region = out.region.empty() ? mask_rect : out.region.Intersect(mask_rect);
  }
  if (!out.region.empty()) {
    const PixelRect inside = out.region.Intersect(camera.ImageRect());
    UNSEEN_CHECK(inside.width() >= 8 && inside.height() >= 8,
                 "{}: the object's region x {} y {} w {} h {} has less than 8x8 pixels inside "
                 "the {}x{} image",
                 command, out.region.x0, out.region.y0, out.region.width(), out.region.height(),
                 camera.width, camera.height);
    const double share = Modeller::ShareInside(out.region, camera);
    UNSEEN_CHECK(share >= Modeller::kMinRegionInside,
                 "{}: the object's region x {} y {} w {} h {} lies {:.0f} % outside the {}x{} "
                 "image: an object cut by the image border cannot be modelled",
                 command, out.region.x0, out.region.y0, out.region.width(), out.region.height(),
                 100.0 * (1.0 - share), camera.width, camera.height);
    out.region = inside;
  }
  if (args.init == "gt") {
    const std::optional<Rigid3d> gt = sequence.GroundTruth(index);
    UNSEEN_CHECK(gt.has_value(),
                 "{}: --init gt but sequence '{}' has no ground truth for frame "
                 "index {}",
                 command, sequence.path(), index);
    out.world_from_obj = *gt;
    return out;
  }
  const std::optional<Rigid3d> start = modeller.InitialPose(frame, out.region, out.mask);
  UNSEEN_CHECK(start.has_value(),
               "{}: no depth measured in the object's region (source {}): cannot place the "
               "object",
               command, ToString(modeller.options().depth.source));
  out.world_from_obj = *start;
  return out;
}

}  // namespace unseen::cli
