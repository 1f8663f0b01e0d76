// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/surface_alignment.h"

#include <gtest/gtest.h>

#include <cmath>

#include "unseen/model/surface_mesh.h"
#include "unseen/model/test_rig_scene.h"

namespace unseen {
namespace {

constexpr double kDeg = M_PI / 180.0;

// The cube's measured depth against the cube rendered 6 mm and 2 deg off: the correction
// brings the measured points onto the rendered cube, i.e. it is that offset.
TEST(SurfaceAlignment, RecoversTheOffsetBetweenMeasuredSurfaceAndModel) {
  const testing::RigScene s = testing::MakeRigScene();
  const RigCamera& cam = s.rig.cameras[0];
  const Rigid3d truth = cam.cam_from_world() * s.world_from_obj;
  const Rigid3d offset(Eigen::Quaterniond(Eigen::AngleAxisd(2 * kDeg, Eigen::Vector3d(0, 1, 0))),
                       Eigen::Vector3d(0.004, -0.003, 0.003));
  const Rigid3d off = offset * truth;  // the model where the tracker put it
  const SurfaceAlignment a =
      AlignSurfaceToModel(s.frame.depths[0], s.object_masks[0], cam.intrinsics, s.object, off,
                          SurfaceAlignmentOptions());
  ASSERT_TRUE(a.ok);
  EXPECT_GT(a.pairs, 500);
  EXPECT_LT(a.rms_after_m, 0.2 * a.rms_before_m);
  // correction * truth-placed points = off-placed model: correction = offset.
  const PoseDifference d = Difference(a.cam_correction, offset);
  EXPECT_LT(d.translation, 5e-4) << a.cam_correction.ToString();
  EXPECT_LT(d.rotation_rad, 0.2 * kDeg) << a.cam_correction.ToString();
}

TEST(SurfaceAlignment, TooFewPairsOrTooLargeACorrectionIsNotTrusted) {
  const testing::RigScene s = testing::MakeRigScene();
  const RigCamera& cam = s.rig.cameras[0];
  const Rigid3d truth = cam.cam_from_world() * s.world_from_obj;
  const cv::Mat nothing = cv::Mat::zeros(s.object_masks[0].size(), CV_8UC1);
  EXPECT_FALSE(AlignSurfaceToModel(s.frame.depths[0], nothing, cam.intrinsics, s.object, truth,
                                   SurfaceAlignmentOptions())
                   .ok);
  SurfaceAlignmentOptions strict;
  strict.max_correction_m = 0.001;
  const Rigid3d off(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.005, 0, 0));
  EXPECT_FALSE(AlignSurfaceToModel(s.frame.depths[0], s.object_masks[0], cam.intrinsics, s.object,
                                   off * truth, strict)
                   .ok);
}

TEST(SurfaceAlignment, AModelBuiltFromTheDepthNeedsNoCorrection) {
  const testing::RigScene s = testing::MakeRigScene();
  const RigCamera& cam = s.rig.cameras[0];
  const Rigid3d truth = cam.cam_from_world() * s.world_from_obj;
  DepthMap map;
  map.depth = s.frame.depths[0];
  map.texturedness = Texturedness(s.frame.images[0]);
  SurfaceMeshOptions mesh_options;
  mesh_options.untextured_vertices = true;
  const std::optional<Mesh> built = BuildSurfaceMesh(map, s.frame.images[0], cam.intrinsics, truth,
                                                     s.object_masks[0], mesh_options);
  ASSERT_TRUE(built.has_value());
  const SurfaceAlignment a =
      AlignSurfaceToModel(s.frame.depths[0], s.object_masks[0], cam.intrinsics, *built, truth,
                          SurfaceAlignmentOptions());
  ASSERT_TRUE(a.ok);
  // Its chords cut the cube's edges by millimetres (1.5 mm RMS off the measured surface at
  // the truth): a slide of a millimetre or so, no more.
  EXPECT_LT(a.shift_m, 2e-3) << a.cam_correction.ToString() << " rms " << a.rms_before_m << " -> "
                             << a.rms_after_m;
}

}  // namespace
}  // namespace unseen
