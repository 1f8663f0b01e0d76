// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The photometric modality, the thesis's tracker (SPEC 3.1): the optical flow between the
// pre-processed virtual image (the model rendered at the round's pose over the input) and
// the input image, at the pixels that pixel selection (pixel_selection.h) keeps.
#pragma once

#include "unseen/track/modality.h"
#include "unseen/track/pixel_selection.h"

namespace unseen {

class PhotometricModality : public CountingModality<SelectionCounts> {
 public:
  explicit PhotometricModality(const PixelSelectionOptions& options = {})
      : CountingModality("photometric"), options_(options) {}
  void AddEquations(const ModalityRound& round) override;

 private:
  PixelSelectionOptions options_;
};

}  // namespace unseen
