// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/photometric_modality.h"

#include <opencv2/imgproc.hpp>

#include "unseen/util/error.h"

namespace unseen {

void PhotometricModality::BeginRound(int num_cameras) {
  CountingModality::BeginRound(num_cameras);
  rounds_.resize(num_cameras);
  for (CameraRound& r : rounds_) {
    r.samples.clear();
    r.input = nullptr;
  }
}

const cv::Mat* PhotometricModality::occluded_blocks(int camera) const {
  if (camera < 0 || camera >= static_cast<int>(rounds_.size())) return nullptr;
  const CameraRound& r = rounds_[camera];
  return r.input ? &r.occluded_blocks : nullptr;
}

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
  CameraRound& r = rounds_[round.camera];
  r.input = &round.input_pre->blurred;
  r.roi = round.roi;
  r.camera = round.level_camera;
  r.origin_in_cam = round.origin_in_cam;
  SelectPixels(in, options_, &CameraEquations(round), &CameraCounts(round), &r.samples,
               &r.occluded_blocks);
  const cv::Mat& mask = round.virtual_image->mask;
  if (remeasure_margin_px_ > 0) {
    const int size = 2 * remeasure_margin_px_ + 1;
    cv::erode(mask, r.interior, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(size, size)),
              cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  } else {
    mask.copyTo(r.interior);
  }
  r.remeasure.resize(r.samples.size());
  for (size_t i = 0; i < r.samples.size(); ++i) {
    const int x = static_cast<int>(r.samples[i].x) - round.roi.x0;
    const int y = static_cast<int>(r.samples[i].y) - round.roi.y0;
    r.remeasure[i] = r.interior.ptr<uint8_t>(y)[x] != 0;
  }
}

void PhotometricModality::MoveBy(const std::vector<Vector6d>& twist_in_cam) {
  UNSEEN_CHECK(twist_in_cam.size() == rounds_.size(),
               "PhotometricModality::MoveBy: {} twists for {} cameras", twist_in_cam.size(),
               rounds_.size());
  for (size_t c = 0; c < rounds_.size(); ++c) {
    const CameraRound& r = rounds_[c];
    FlowEquations& eq = CameraEquations(static_cast<int>(c));
    if (eq.size() == 0 || !r.input) continue;
    UNSEEN_CHECK(static_cast<int>(r.samples.size()) == eq.size(),
                 "PhotometricModality::MoveBy: {} samples for {} equations", r.samples.size(),
                 eq.size());
    const std::vector<float>& rhs = RoundRhs(static_cast<int>(c));
    const Eigen::Matrix3f rotation =
        ExpSO3(twist_in_cam[c].tail<3>()).toRotationMatrix().cast<float>();
    const Eigen::Vector3f translation = twist_in_cam[c].head<3>().cast<float>();
    const Eigen::Matrix<float, 6, 1> t = twist_in_cam[c].cast<float>();
    const Eigen::Vector3f origin = r.origin_in_cam.cast<float>();
    const float fx = float(r.camera.fx), fy = float(r.camera.fy);
    const float cx = float(r.camera.cx), cy = float(r.camera.cy);
    const cv::Mat& image = *r.input;
    const float max_x = float(image.cols - 1), max_y = float(image.rows - 1);
    for (int i = 0; i < eq.size(); ++i) {
      const PhotometricSample& s = r.samples[i];
      // The surface point seen at the sample, moved about the object's origin (4.4).
      const Eigen::Vector3f point((s.x - cx) * s.z / fx, (s.y - cy) * s.z / fy, s.z);
      const Eigen::Vector3f moved = origin + rotation * (point - origin) + translation;
      const float u = fx * moved.x() / moved.z() + cx - float(r.roi.x0);
      const float v = fy * moved.y() / moved.z() + cy - float(r.roi.y0);
      if (!r.remeasure[i] || !(moved.z() > 0.0f) ||
          !(u >= 0.0f && v >= 0.0f && u < max_x && v < max_y)) {
        eq.rhs[i] = rhs[i] - eq.rows[i].dot(t);
        continue;
      }
      const int x0 = static_cast<int>(u), y0 = static_cast<int>(v);
      const float ax = u - float(x0), ay = v - float(y0);
      const float* p0 = image.ptr<float>(y0) + 3 * x0;
      const float* p1 = image.ptr<float>(y0 + 1) + 3 * x0;
      float value = 0.0f;
      for (int j = 0; j < 3; ++j) {
        const float top = p0[j] + ax * (p0[3 + j] - p0[j]);
        const float bottom = p1[j] + ax * (p1[3 + j] - p1[j]);
        value += s.weight[j] * (top + ay * (bottom - top));
      }
      eq.rhs[i] = -(value - s.virtual_value);
    }
  }
}

}  // namespace unseen
