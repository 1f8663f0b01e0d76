// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/photometric_modality.h"

#include "unseen/util/error.h"

namespace unseen {

void PhotometricModality::AddEquations(const ModalityRound& round) {
  UNSEEN_CHECK(round.virtual_pre && round.input_pre && round.photometric_region &&
                   round.photometric_depth,
               "PhotometricModality: the round lacks the pre-processed images");
  SelectionInput in;
  in.virtual_image = round.virtual_pre;
  in.input_image = round.input_pre;
  in.region = round.photometric_region;
  in.depth = round.photometric_depth;
  in.roi = round.roi;
  in.camera = round.level_camera;
  in.origin_in_cam = round.origin_in_cam;
  SelectPixels(in, options_, &CameraEquations(round), &CameraCounts(round));
}

}  // namespace unseen
