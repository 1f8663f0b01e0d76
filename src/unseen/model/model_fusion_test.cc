// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/model_fusion.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "unseen/mesh/primitives.h"
#include "unseen/render/rasterizer.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

// One RGB-D camera at the origin looking along +z at the lettered 100 mm cube 0.6 m away
// before a wall, the cube turned about the vertical by a given angle.
class Fusion : public ::testing::Test {
 protected:
  void SetUp() override {
    rig_.cameras.push_back({"cam0", PinholeCamera::Centered(320, 240, 400.0), Rigid3d()});
    options_.depth.source = DepthSourceKind::kSensor;
    modeller_ = std::make_unique<Modeller>(rig_, 0, options_);
  }
  Rigid3d Truth(double turn_deg) const {
    const Eigen::Quaterniond q(
        Eigen::AngleAxisd(turn_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()) *
        Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitX()));
    return Rigid3d(q, Eigen::Vector3d(0.0, 0.0, 0.6));
  }
  RenderBuffers See(const Mesh& mesh, const Rigid3d& cam_from_obj) const {
    RenderBuffers buffers;
    Render(mesh, camera(), cam_from_obj, camera().ImageRect(), RenderOptions(), &buffers);
    return buffers;
  }
  Frame Image(double turn_deg) const {
    const RenderBuffers object = See(cube_, Truth(turn_deg));
    const RenderBuffers wall =
        See(wall_, Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 1.0)));
    Frame frame;
    frame.images.push_back(wall.color.clone());
    object.color.copyTo(frame.images[0], object.mask);
    frame.depths.push_back(wall.depth.clone());
    object.depth.copyTo(frame.depths[0], object.mask);
    return frame;
  }
  ModelBuild Build(double turn_deg, const Rigid3d& world_from_obj) const {
    ModelBuild build = modeller_->Build(Image(turn_deg), world_from_obj, PixelRect());
    EXPECT_TRUE(build.ok()) << build.why;
    return build;
  }
  // Intersection over union of the cube's and `model`'s silhouettes at `turn_deg`.
  double Iou(const Mesh& model, double turn_deg) const {
    const RenderBuffers truth = See(cube_, Truth(turn_deg)), got = See(model, Truth(turn_deg));
    return double(cv::countNonZero(truth.mask & got.mask)) /
           cv::countNonZero(truth.mask | got.mask);
  }
  const PinholeCamera& camera() const { return rig_.cameras[0].intrinsics; }

  Rig rig_;
  ModellerOptions options_;
  std::unique_ptr<Modeller> modeller_;
  const Mesh cube_ = MakeLetteredCube(0.1, 128);
  const Mesh wall_ = MakeTexturedBox(Eigen::Vector3d(1.6, 1.2, 0.02));
};

TEST_F(Fusion, TheModelGrowsAsTheObjectTurnsAndKeepsItsFrame) {
  ModelFusion fusion(rig_.cameras[0], 0.15, options_.fusion);
  std::string why;
  const ModelBuild first = Build(0.0, Truth(0.0));
  const std::optional<Mesh> one = fusion.Fuse(first, &why);
  ASSERT_TRUE(one.has_value()) << why;
  EXPECT_GT(Iou(*one, 0.0), 0.85);   // the outline pixels only carve: a pixel short all round
  EXPECT_LT(Iou(*one, 150.0), 0.5);  // the far side was never seen
  std::optional<Mesh> model;
  for (double turn : {50.0, 100.0, 150.0}) {
    model = fusion.Fuse(Build(turn, Truth(turn)), &why);
    ASSERT_TRUE(model.has_value()) << why;
  }
  EXPECT_EQ(fusion.report().fused, 4);
  EXPECT_GE(fusion.report().key_views, 3);
  EXPECT_LE(model->num_triangles(), options_.fusion.max_triangles);
  // Every side seen is in the model, where the cube is, with a view's texture on it.
  for (double turn : {0.0, 50.0, 100.0, 150.0}) EXPECT_GT(Iou(*model, turn), 0.85) << turn;
  int off = 0;
  for (const Eigen::Vector3f& v : model->vertices) {
    off += std::abs(v.cwiseAbs().maxCoeff() - 0.05f) > 2.0f * fusion.volume()->voxel_m();
  }
  EXPECT_LT(off, 0.02 * model->num_vertices());
  const RenderBuffers seen = See(*model, Truth(100.0));
  const RenderBuffers truth = See(cube_, Truth(100.0));
  EXPECT_LT(cv::norm(seen.color, truth.color, cv::NORM_L1, seen.mask & truth.mask) /
                (3.0 * cv::countNonZero(seen.mask & truth.mask)),
            0.08);
}

TEST_F(Fusion, PosesWithTrackingErrorsAverageOut) {
  // Builds at poses off by up to 3 mm (a tracker's error): the fused surface stays near
  // the cube, where a model rebuilt at the last pose would be off by that pose's error.
  ModelFusion fusion(rig_.cameras[0], 0.15, options_.fusion);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> error(-0.003, 0.003);
  std::string why;
  std::optional<Mesh> model;
  for (int i = 0; i < 8; ++i) {
    const double turn = 10.0 * i;
    const Rigid3d tracked(
        Truth(turn).rotation(),
        Truth(turn).translation() + Eigen::Vector3d(error(random), error(random), error(random)));
    model = fusion.Fuse(Build(turn, tracked), &why);
    ASSERT_TRUE(model.has_value()) << why;
  }
  double sum_off = 0.0;
  for (const Eigen::Vector3f& v : model->vertices) {
    sum_off += std::abs(v.cwiseAbs().maxCoeff() - 0.05f);
  }
  EXPECT_LT(sum_off / model->num_vertices(), 0.0015);
}

TEST_F(Fusion, SparseDepthGivesNoFusedModelButTheBuildStands) {
  // A far object or a sensor's holes: depth on a third of the pixels, at random. The
  // build spans the holes with its triangulation; the volume gets scattered voxels whose
  // surface is no model.
  Frame frame = Image(20.0);
  cv::Mat kept(frame.depths[0].size(), CV_8UC1);
  cv::RNG random(3);
  random.fill(kept, cv::RNG::UNIFORM, 0, 3);
  frame.depths[0].setTo(0.0f, kept != 0);
  const ModelBuild build = modeller_->Build(frame, Truth(20.0), PixelRect());
  ASSERT_TRUE(build.ok()) << build.why;
  ModelFusion fusion(rig_.cameras[0], 0.15, options_.fusion);
  std::string why;
  EXPECT_FALSE(fusion.Fuse(build, &why).has_value());
  EXPECT_NE(why.find("fusion.min_coverage"), std::string::npos) << "[" << why << "]";
  EXPECT_LT(fusion.report().coverage, options_.fusion.min_coverage);
  EXPECT_GT(Iou(*build.mesh, 20.0), 0.6);  // what the tracker is handed instead
  // Dense depth of the same view fuses into a model covering what the build covers.
  ModelFusion dense(rig_.cameras[0], 0.15, options_.fusion);
  ASSERT_TRUE(dense.Fuse(Build(20.0, Truth(20.0)), &why).has_value()) << why;
  EXPECT_GT(dense.report().coverage, 0.9);
}

TEST_F(Fusion, BadOptionsAndFailedBuildsAreErrors) {
  ModelFusionOptions bad = options_.fusion;
  bad.max_key_views = 0;
  EXPECT_THROW(bad.Check(), Error);
  bad = options_.fusion;
  bad.min_coverage = 1.5;
  EXPECT_THROW(bad.Check(), Error);
  bad = options_.fusion;
  bad.volume.voxels_per_side = 4;
  EXPECT_THROW(ModelFusion(rig_.cameras[0], 0.15, bad), Error);
  EXPECT_THROW(ModelFusion(rig_.cameras[0], 0.0, options_.fusion), Error);
  ModelFusion fusion(rig_.cameras[0], 0.15, options_.fusion);
  std::string why;
  EXPECT_THROW(fusion.Fuse(ModelBuild(), &why), Error);
  EXPECT_EQ(fusion.volume(), nullptr);
}

}  // namespace
}  // namespace unseen
