// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "tools/unseen/known_object.h"

#include "tools/unseen/unknown_object.h"
#include "unseen/select/interest_filter_bank.h"
#include "unseen/select/motion_segmentation.h"
#include "unseen/select/region_selection.h"
#include "unseen/system/system.h"
#include "unseen/util/error.h"
#include "unseen/util/logging.h"

namespace unseen::cli {

KnownObjectStart FindKnownObject(const Sequence& sequence, int first_frame, const std::string& roi,
                                 const std::string& filters, Tracker* tracker,
                                 const std::string& command) {
  const int camera = sequence.reference_camera();
  const RigCamera& rig_camera = sequence.rig().cameras[camera];
  KnownModelPoser poser(tracker);
  KnownObjectStart start;
  if (!roi.empty()) {
    const PixelRect box = ParseRoi(roi, command);
    start.index = first_frame;
    start.frame = sequence.ReadFrame(first_frame);
    start.pose = poser.Find(start.frame, camera, box);
    UNSEEN_CHECK(start.pose.found,
                 "{}: --init auto: no confident pose of the model in --roi {} of frame {}: {}",
                 command, roi, start.frame.frame_id, start.pose.BriefReport());
    UNSEEN_LOG_INFO("{}: --init auto: frame {}: {}", command, start.frame.frame_id,
                    start.pose.BriefReport());
    return start;
  }

  InterestFilterBank bank;
  if (filters.empty()) {
    bank.Add(std::make_unique<MotionFilter>(MotionFilterOptions()));
  } else {
    bank = LoadInterestFilterBank(filters);
  }
  // Regions of one motion each (block-based, SPEC 4.2), selected as `unseen run` selects
  // them (SystemOptions: motion regions hold the whole object while the background model
  // flags mostly its edges).
  MotionSegmenter segmenter;
  const RegionSelectionOptions selection = SystemOptions().selection;
  int tried = 0;
  for (int i = 0; i < sequence.num_frames(); ++i) {
    Frame frame = sequence.ReadFrame(i);
    FilterFrame in;
    in.image = frame.images[camera];
    if (!frame.depths.empty()) in.depth = frame.depths[camera];
    in.camera = rig_camera.intrinsics;
    in.world_from_cam = rig_camera.world_from_cam;
    in.time_s = frame.time_s;
    // The bank learns from every frame (the background model), also before the first.
    const cv::Mat interest = bank.Apply(in);
    const cv::Mat regions = segmenter.Segment(in.image, interest);
    if (i < first_frame || !bank.ready()) continue;
    const RegionSelection s =
        SelectRegion(regions, interest, cv::Mat(), in.depth, rig_camera.intrinsics, selection);
    if (!s.found()) continue;
    ++tried;
    const PixelRect box = segmenter.ObjectBox(s.object().box);
    KnownModelPoseResult pose = poser.Find(frame, camera, box);
    UNSEEN_LOG_INFO("{}: --init auto: frame {}: region {}x{} at ({}, {}): {}", command,
                    frame.frame_id, box.width(), box.height(), box.x0, box.y0, pose.BriefReport());
    if (!pose.found) continue;
    start.index = i;
    start.frame = std::move(frame);
    start.pose = std::move(pose);
    return start;
  }
  ThrowError(
      "{}: --init auto: the model was not found in '{}' ({} selected regions tried from "
      "frame index {}; give --roi, or --filters for another interest filter bank)",
      command, sequence.path(), tried, first_frame);
}

}  // namespace unseen::cli
