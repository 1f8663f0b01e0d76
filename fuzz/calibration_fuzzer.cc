// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The camera calibration readers (camera/calibration_io.h) on one file: the input is the
// file (OpenCV YAML/XML/JSON or ROS camera_info YAML), read by LoadCameraCalibration,
// LoadOpenCvCalibration and LoadRosCameraInfo. A camera they return passes
// PinholeCamera::Check.
#include "fuzz/fuzz_support.h"
#include "unseen/camera/calibration_io.h"

namespace {

void CheckCamera(const unseen::PinholeCamera& camera, const std::string& reader) {
  try {
    camera.Check();
  } catch (const unseen::Error& e) {
    unseen::fuzz::Fail(reader + " returned a camera that fails its check: " + e.what());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace unseen;
  fuzz::Init();
  static const fuzz::Scratch scratch("calibration");
  const std::string path = scratch.Write("calibration.yaml", fuzz::AsText(data, size));
  fuzz::ExpectReaderContract("LoadCameraCalibration", path, [&] {
    CheckCamera(LoadCameraCalibration(path), "LoadCameraCalibration");
  });
  fuzz::ExpectReaderContract("LoadOpenCvCalibration", path, [&] {
    CheckCamera(LoadOpenCvCalibration(path), "LoadOpenCvCalibration");
  });
  fuzz::ExpectReaderContract("LoadRosCameraInfo", path,
                             [&] { CheckCamera(LoadRosCameraInfo(path), "LoadRosCameraInfo"); });
  return 0;
}
