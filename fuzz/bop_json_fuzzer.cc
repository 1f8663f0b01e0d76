// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The BOP JSON helpers (io/bop_json.h) and ReadBopSceneGtAsPoses (io/pose_stream.h) on one
// JSON file (scene_gt.json, scene_camera.json, models_info.json, ...): the input is the
// file. ReadJsonFile parses it, ParseFrameId takes every top-level key, and the file is
// read as a scene_gt.json for the first object and for object 1.
#include <cmath>

#include "fuzz/fuzz_support.h"
#include "unseen/io/bop_json.h"
#include "unseen/io/pose_stream.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace unseen;
  fuzz::Init();
  static const fuzz::Scratch scratch("bop_json");
  const std::string path = scratch.Write("scene_gt.json", fuzz::AsText(data, size));
  fuzz::ExpectReaderContract("ReadJsonFile", path, [&] {
    const nlohmann::json json = bop::ReadJsonFile(path);
    if (!json.is_object()) return;
    for (const auto& item : json.items()) {
      fuzz::ExpectReaderContract("ParseFrameId", path, [&] {
        const int id = bop::ParseFrameId(item.key(), path);
        UNSEEN_FUZZ_EXPECT(id >= 0 && std::to_string(id).size() <= item.key().size(),
                           "key '{}' gave frame id {}", item.key(), id);
      });
    }
  });
  for (int obj_id : {0, 1}) {
    fuzz::ExpectReaderContract("ReadBopSceneGtAsPoses", path, [&] {
      const double fps = 30.0;
      int previous = -1;
      for (const PoseRecord& r : ReadBopSceneGtAsPoses(path, Rigid3d(), obj_id, fps)) {
        UNSEEN_FUZZ_EXPECT(r.frame > previous, "frame {} after frame {}", r.frame, previous);
        previous = r.frame;
        UNSEEN_FUZZ_EXPECT(r.world_from_obj.IsValid(), "frame {} pose {}", r.frame,
                           r.world_from_obj.ToString());
        UNSEEN_FUZZ_EXPECT(std::isfinite(r.time_s), "frame {} time {}", r.frame, r.time_s);
      }
    });
  }
  return 0;
}
