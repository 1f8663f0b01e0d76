// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// ReadPoseStream (io/pose_stream.h) on a CSV or JSON-lines pose stream: the input is the
// file. What it accepts must be what it documents: unique non-negative frames, finite
// times, confidences in [0, 1], valid poses, non-negative processing times.
#include <cmath>
#include <set>

#include "fuzz/fuzz_support.h"
#include "unseen/io/pose_stream.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace unseen;
  fuzz::Init();
  static const fuzz::Scratch scratch("pose_stream");
  const std::string path = scratch.Write("poses.csv", fuzz::AsText(data, size));
  fuzz::ExpectReaderContract("ReadPoseStream", path, [&] {
    std::set<int> frames;
    for (const PoseRecord& r : ReadPoseStream(path)) {
      UNSEEN_FUZZ_EXPECT(r.frame >= 0 && frames.insert(r.frame).second, "frame {}", r.frame);
      UNSEEN_FUZZ_EXPECT(std::isfinite(r.time_s), "frame {} time {}", r.frame, r.time_s);
      UNSEEN_FUZZ_EXPECT(r.confidence >= 0.0 && r.confidence <= 1.0, "frame {} confidence {}",
                         r.frame, r.confidence);
      UNSEEN_FUZZ_EXPECT(r.world_from_obj.IsValid(), "frame {} pose {}", r.frame,
                         r.world_from_obj.ToString());
      UNSEEN_FUZZ_EXPECT(!r.process_ms || (std::isfinite(*r.process_ms) && *r.process_ms >= 0.0),
                         "frame {} process_ms {}", r.frame, *r.process_ms);
    }
  });
  return 0;
}
