// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/modality.h"

#include "unseen/util/error.h"

namespace unseen {

const std::vector<float>& Modality::RoundRhs(int camera) {
  if (round_rhs_.empty()) {
    round_rhs_.resize(equations_.cameras.size());
    for (size_t c = 0; c < equations_.cameras.size(); ++c) {
      round_rhs_[c] = equations_.cameras[c].rhs;
    }
  }
  return round_rhs_[camera];
}

void Modality::MoveBy(const std::vector<Vector6d>& twist_in_cam) {
  UNSEEN_CHECK(twist_in_cam.size() == equations_.cameras.size(),
               "Modality::MoveBy: {} twists for {} cameras", twist_in_cam.size(),
               equations_.cameras.size());
  for (size_t c = 0; c < equations_.cameras.size(); ++c) {
    FlowEquations& eq = equations_.cameras[c];
    if (eq.size() == 0) continue;
    const std::vector<float>& rhs = RoundRhs(static_cast<int>(c));
    const Eigen::Matrix<float, 6, 1> t = twist_in_cam[c].cast<float>();
    for (int i = 0; i < eq.size(); ++i) eq.rhs[i] = rhs[i] - eq.rows[i].dot(t);
  }
}

}  // namespace unseen
