// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/model/modeller.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "unseen/mesh/primitives.h"
#include "unseen/model/test_rig_scene.h"
#include "unseen/render/rasterizer.h"
#include "unseen/track/tracker.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

using testing::MakeRigScene;
using testing::RigScene;

constexpr double kDeg = M_PI / 180.0;

// Intersection over union of two masks (CV_8UC1).
double Iou(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat both, either;
  cv::bitwise_and(a, b, both);
  cv::bitwise_or(a, b, either);
  return double(cv::countNonZero(both)) / cv::countNonZero(either);
}

class ModellerScene : public ::testing::TestWithParam<DepthSourceKind> {
 protected:
  static void SetUpTestSuite() { scene_ = new RigScene(MakeRigScene()); }
  static void TearDownTestSuite() {
    delete scene_;
    scene_ = nullptr;
  }
  static PixelRect ObjectRegion(int margin) {
    const cv::Rect box = cv::boundingRect(scene_->object_masks[0]);
    return PixelRect{box.x, box.y, box.x + box.width, box.y + box.height}.Grow(margin);
  }
  // The first camera's sensor depth (dense), that camera and the object's origin in it.
  static DepthMap SensorDepth() {
    DepthMap map;
    map.depth = scene_->frame.depths[0].clone();
    map.dense = true;
    return map;
  }
  static const PinholeCamera& Camera() { return scene_->rig.cameras[0].intrinsics; }
  static Eigen::Vector3d OriginInCamera() {
    return (scene_->rig.cameras[0].cam_from_world() * scene_->world_from_obj).translation();
  }
  static RigScene* scene_;
};
RigScene* ModellerScene::scene_ = nullptr;

// Built at the true object frame from the object's region (the wall behind it included),
// the model lies on the cube, covers most of it, and tracks it: from a pose 8 mm and 3 deg
// off, aligning the model to the frame returns to the truth.
TEST_P(ModellerScene, BuildsATrackableModelOfTheObjectOnly) {
  const RigScene& s = *scene_;
  ModellerOptions options;
  options.depth.source = GetParam();
  const Modeller modeller(s.rig, 0, options);
  const ModelBuild build = modeller.Build(s.frame, s.world_from_obj, ObjectRegion(20));
  ASSERT_TRUE(build.ok()) << build.why;
  const Mesh& mesh = *build.mesh;
  EXPECT_GT(mesh.num_triangles(), 30);
  EXPECT_EQ(build.report.triangles, mesh.num_triangles());
  std::vector<double> off;
  for (const Eigen::Vector3f& v : mesh.vertices) {
    off.push_back(std::abs(v.cwiseAbs().maxCoeff() - 0.05));
  }
  std::sort(off.begin(), off.end());
  EXPECT_LT(off[off.size() / 2], 0.004);
  EXPECT_LT(off[off.size() * 9 / 10], 0.012);
  const RigCamera& cam = s.rig.cameras[0];
  RenderBuffers r;
  Render(mesh, cam.intrinsics, cam.cam_from_world() * s.world_from_obj, cam.intrinsics.ImageRect(),
         RenderOptions(), &r);
  cv::Mat covered;
  cv::bitwise_and(r.mask, s.object_masks[0], covered);
  EXPECT_GT(cv::countNonZero(covered), 0.5 * cv::countNonZero(s.object_masks[0]));

  Rig one;
  one.cameras.push_back(cam);
  Tracker tracker(one, mesh);
  const Rigid3d start(Eigen::AngleAxisd(3 * kDeg, Eigen::Vector3d(1, 1, 0).normalized()) *
                          s.world_from_obj.rotation(),
                      s.world_from_obj.translation() + Eigen::Vector3d(0.006, -0.005, 0.0));
  const TrackResult aligned = tracker.Align({s.frame.images[0]}, start);
  const PoseDifference e = Difference(aligned.world_from_obj, s.world_from_obj);
  EXPECT_LT(e.translation, 0.003) << aligned.BriefReport();
  EXPECT_LT(e.rotation_rad, 1.0 * kDeg) << aligned.BriefReport();
}

INSTANTIATE_TEST_SUITE_P(AllSources, ModellerScene,
                         ::testing::Values(DepthSourceKind::kPlaneSweep, DepthSourceKind::kStereo,
                                           DepthSourceKind::kSensor),
                         [](const auto& info) { return ToString(info.param); });

TEST_F(ModellerScene, TheInitialFrameSitsJustBehindTheRegionsSurface) {
  const RigScene& s = *scene_;
  ModellerOptions options;
  options.depth.source = DepthSourceKind::kSensor;
  const Modeller modeller(s.rig, 0, options);
  const std::optional<Rigid3d> pose =
      modeller.InitialPose(s.frame, ObjectRegion(0), s.object_masks[0]);
  ASSERT_TRUE(pose.has_value());
  // The camera's axes; about the cube's centre (the visible surface is ~4-5 cm before it).
  EXPECT_LT(
      Difference(*pose, Rigid3d(Eigen::Quaterniond::Identity(), pose->translation())).rotation_rad,
      1e-9);
  EXPECT_LT((pose->translation() - s.world_from_obj.translation()).norm(), 0.04);
  // A region without depth has no initial frame.
  Frame no_depth = s.frame;
  no_depth.depths[0] = cv::Mat(s.frame.depths[0].size(), CV_32FC1, cv::Scalar(0));  // not in place
  EXPECT_FALSE(modeller.InitialPose(no_depth, ObjectRegion(0)).has_value());
}

// Three cameras 35 degrees apart on a circle of 0.65 m about a 60 mm lettered cube, toed in
// towards it, before a wall of black and white blobs 1.8 m away. Placing the frame searches
// the whole depth range (0.1-5 m): with the object's 64 planes, neighbouring planes are
// pixels apart at the cube for these baselines, the match aliases and the origin lands
// 7 cm off (256 planes: 1.3 cm).
TEST(ModellerInitialPose, AWideRigPlacesTheFrameAtTheObjectsDepth) {
  const PinholeCamera cam = PinholeCamera::Centered(320, 240, 400.0);
  const Eigen::Vector3d centre(0.0, 0.0, 0.65);
  Rig rig;
  for (const double deg : {0.0, 35.0, -35.0}) {
    const Eigen::Quaterniond turn(Eigen::AngleAxisd(deg * kDeg, Eigen::Vector3d::UnitY()));
    // The camera on the circle about `centre`, its optical axis through it.
    const Eigen::Vector3d position = centre - turn * Eigen::Vector3d(0.0, 0.0, 0.65);
    rig.cameras.push_back({fmt::format("cam{}", rig.size()), cam, Rigid3d(turn, position)});
  }
  const Mesh cube = MakeLetteredCube(0.06, 128);
  const Rigid3d world_from_obj(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()) *
                                   Eigen::Quaterniond(Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitX())),
                               centre);
  // The wall: black and white blobs with fine speckle (a high-contrast photo).
  cv::Mat noise(30, 40, CV_32FC1), blobs, speckle(600, 800, CV_32FC1);
  cv::RNG rng(3);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::resize(noise, blobs, speckle.size(), 0.0, 0.0, cv::INTER_CUBIC);
  rng.fill(speckle, cv::RNG::UNIFORM, 0.0, 0.3);
  cv::Mat grey = (blobs > 0.5) / 255;
  grey.convertTo(grey, CV_32FC1, 0.7);
  grey += speckle;
  Mesh wall;
  wall.vertices = {{-2.0f, -1.5f, 0.0f}, {2.0f, -1.5f, 0.0f}, {2.0f, 1.5f, 0.0f}, {-2.0f, 1.5f, 0.0f}};
  wall.triangles = {{0, 2, 1}, {0, 3, 2}};
  wall.uvs = {{0.0f, 1.0f}, {1.0f, 1.0f}, {1.0f, 0.0f}, {0.0f, 0.0f}};
  Material paper;
  cv::cvtColor(grey, paper.texture, cv::COLOR_GRAY2BGR);
  wall.materials = {paper};
  wall.triangle_materials = {0, 0};
  const Rigid3d world_from_wall(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 1.8));
  Frame frame;
  for (const RigCamera& c : rig.cameras) {
    RenderBuffers behind, seen;
    Render(wall, cam, c.cam_from_world() * world_from_wall, cam.ImageRect(), RenderOptions(),
           &behind);
    Render(cube, cam, c.cam_from_world() * world_from_obj, cam.ImageRect(), RenderOptions(), &seen);
    cv::Mat image = behind.color.clone();
    seen.color.copyTo(image, seen.mask);
    frame.images.push_back(image);
  }
  const std::optional<PixelRect> region = cam.SphereRect(centre, 0.09);
  ASSERT_TRUE(region.has_value());
  auto depth_error = [&](int planes) {
    ModellerOptions options;
    options.depth.source = DepthSourceKind::kPlaneSweep;
    options.initial_pose_planes = planes;
    const std::optional<Rigid3d> pose = Modeller(rig, 0, options).InitialPose(frame, *region);
    return pose ? std::abs(pose->translation().z() - centre.z()) : 1e9;
  };
  // The visible surface is 3-4 cm before the cube's centre, the origin 2 cm behind it.
  EXPECT_LT(depth_error(ModellerOptions().initial_pose_planes), 0.03);
  EXPECT_GT(depth_error(64), 0.03) << "64 planes no longer alias on this rig";
}

TEST_F(ModellerScene, SegmentationDropsTheFloorTheObjectStandsOn) {
  const RigScene& s = *scene_;
  const RigCamera& cam = s.rig.cameras[0];
  // The cube resting on a floor that the camera sees from 45 deg above, turned about the
  // floor's normal.
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitX()).matrix();
  const Eigen::Vector3d up = tilt * Eigen::Vector3d(0, -1, 0);  // towards the camera
  const Eigen::Vector3d on_floor(0.0, 0.03, 0.6);
  const Rigid3d cam_from_obj(
      Eigen::Quaterniond(tilt * Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()).matrix()),
      on_floor + 0.05 * up);
  const Mesh floor = MakeTexturedBox(Eigen::Vector3d(1.0, 0.02, 1.0));
  const Rigid3d cam_from_floor(Eigen::Quaterniond(tilt), on_floor - 0.0105 * up);
  RenderBuffers floor_buffers, cube_buffers;
  Render(floor, cam.intrinsics, cam_from_floor, cam.intrinsics.ImageRect(), RenderOptions(),
         &floor_buffers);
  Render(s.object, cam.intrinsics, cam_from_obj, cam.intrinsics.ImageRect(), RenderOptions(),
         &cube_buffers);
  const cv::Rect box = cv::boundingRect(cube_buffers.mask);
  const PixelRect region = PixelRect{box.x, box.y, box.x + box.width, box.y + box.height}.Grow(40);
  DepthMap map;
  map.depth = floor_buffers.depth.clone();
  cube_buffers.depth.copyTo(map.depth, cube_buffers.mask);
  map.dense = true;  // a sensor's
  SegmentationReport report;
  const cv::Mat mask = SegmentObject(map, cam.intrinsics, region, cam_from_obj.translation(),
                                     cv::Mat(), SegmentationOptions(), &report);
  EXPECT_TRUE(report.plane_found);
  EXPECT_GT(report.on_plane, 0);
  auto iou = [&](const cv::Mat& m) { return Iou(m, cube_buffers.mask); };
  EXPECT_GT(iou(mask), 0.9);
  // Without the plane the floor is connected to the cube and stays.
  SegmentationOptions no_plane;
  no_plane.remove_support_plane = false;
  EXPECT_LT(iou(SegmentObject(map, cam.intrinsics, region, cam_from_obj.translation(), cv::Mat(),
                              no_plane)),
            0.8);
}

TEST_F(ModellerScene, SegmentationKeepsALargeFlatSideOfTheObject) {
  const RigScene& s = *scene_;
  const RigCamera& cam = s.rig.cameras[0];
  // A van-like box, 240 x 110 x 110 mm, its long side to the camera at 0.6 m (turned 20 deg
  // so that its front shows too): the side's plane reaches past the support test's rim as
  // a floor would, but the rest of the box lies behind it, not before it.
  const Mesh van = MakeTexturedBox(Eigen::Vector3d(0.24, 0.11, 0.11));
  const Rigid3d cam_from_obj(Eigen::Quaterniond(Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitY())),
                             Eigen::Vector3d(0.0, 0.0, 0.6));
  RenderBuffers buffers;
  Render(van, cam.intrinsics, cam_from_obj, cam.intrinsics.ImageRect(), RenderOptions(), &buffers);
  const cv::Rect box = cv::boundingRect(buffers.mask);
  const PixelRect region = PixelRect{box.x, box.y, box.x + box.width, box.y + box.height}.Grow(20);
  DepthMap map;
  map.depth = buffers.depth.clone();
  map.dense = true;
  SegmentationReport report;
  const cv::Mat mask = SegmentObject(map, cam.intrinsics, region, cam_from_obj.translation(),
                                     cv::Mat(), SegmentationOptions(), &report);
  EXPECT_FALSE(report.plane_found);
  EXPECT_EQ(report.on_plane, 0);
  EXPECT_GT(Iou(mask, buffers.mask), 0.95);
}

TEST_F(ModellerScene, SegmentationSeparatesTheObjectFromTheWallBehindIt) {
  const RigScene& s = *scene_;
  DepthMap map = SensorDepth();
  const PinholeCamera& camera = Camera();
  const Eigen::Vector3d origin = OriginInCamera();
  // A radius that takes in the wall, and no plane removal: the wall is not connected to the
  // object in depth.
  SegmentationOptions options;
  options.max_radius_m = 0.6;
  options.remove_support_plane = false;
  SegmentationReport report;
  const cv::Mat mask =
      SegmentObject(map, camera, ObjectRegion(40), origin, cv::Mat(), options, &report);
  EXPECT_TRUE(report.dense);
  EXPECT_FALSE(report.plane_found);
  EXPECT_GT(report.unconnected, 0);
  EXPECT_GT(Iou(mask, s.object_masks[0]), 0.9);
}

TEST_F(ModellerScene, SegmentationIgnoresASensorsIslandNearerTheOriginThanTheFace) {
  const RigScene& s = *scene_;
  DepthMap map = SensorDepth();
  const PinholeCamera& camera = Camera();
  const Eigen::Vector3d origin = OriginInCamera();
  // Amid the object's face, a two-pixel island measured at the object's centre, centimetres
  // behind the face (a thin part seen through a gap, or a sensor's stray measurement): not
  // connected to the face in depth, and nearer the origin than any of the face's points.
  const cv::Rect box = cv::boundingRect(s.object_masks[0]);
  const Eigen::Vector2d island_px(box.x + box.width / 2, box.y + box.height / 2);
  const Eigen::Vector3d ray = camera.Unproject(island_px, 1.0);
  const double z = origin.dot(ray) / ray.squaredNorm();  // the ray's point nearest the origin
  ASSERT_LT((z * ray - origin).norm(), 0.01);
  map.depth.at<float>(int(island_px.y()), int(island_px.x())) = static_cast<float>(z);
  map.depth.at<float>(int(island_px.y()), int(island_px.x()) + 1) = static_cast<float>(z);
  SegmentationOptions options;
  options.remove_support_plane = false;
  const double face_m = [&] {
    double d = 1e9;
    for (int y = 0; y < camera.height; ++y) {
      for (int x = 0; x < camera.width; ++x) {
        if (!s.object_masks[0].at<uint8_t>(y, x)) continue;
        const Eigen::Vector3d p =
            camera.Unproject(Eigen::Vector2d(x, y), s.frame.depths[0].at<float>(y, x));
        d = std::min(d, (p - origin).norm());
      }
    }
    return d;
  }();
  ASSERT_GT(face_m, 0.02) << "the island must be nearer the origin than the face";
  const PixelRect region = ObjectRegion(40);
  EXPECT_GT(Iou(SegmentObject(map, camera, region, origin, cv::Mat(), options), s.object_masks[0]),
            0.9);
  // Taken as a seed however small, the island alone would be the object.
  options.min_component_share = 0.0;
  EXPECT_LT(Iou(SegmentObject(map, camera, region, origin, cv::Mat(), options), s.object_masks[0]),
            0.1);
}

TEST_F(ModellerScene, ASensorsDepthThinnedToScatteredPixelsStillGivesTheObject) {
  const RigScene& s = *scene_;
  DepthMap map = SensorDepth();
  const PinholeCamera& camera = Camera();
  const Eigen::Vector3d origin = OriginInCamera();
  // A sensor far from the object, or a dark one: three pixels of four lost, at random, so
  // that the measured ones touch one another only here and there.
  cv::Mat keep(map.depth.size(), CV_32FC1);
  cv::RNG rng(7);
  rng.fill(keep, cv::RNG::UNIFORM, 0.0, 1.0);
  map.depth.setTo(0.0f, keep > 0.25f);
  SegmentationOptions options;
  options.remove_support_plane = false;
  const PixelRect region = ObjectRegion(40);
  SegmentationReport report;
  const cv::Mat mask = SegmentObject(map, camera, region, origin, cv::Mat(), options, &report);
  EXPECT_TRUE(report.fragmented);
  EXPECT_FALSE(report.dense);
  EXPECT_GT(Iou(mask, s.object_masks[0]), 0.8);
  // Taken as dense (its pixels connected to their eight neighbours only), one island.
  options.min_connected_share = 0.0;
  const cv::Mat islands = SegmentObject(map, camera, region, origin, cv::Mat(), options, &report);
  EXPECT_FALSE(report.fragmented);
  EXPECT_LT(cv::countNonZero(islands), 0.1 * cv::countNonZero(s.object_masks[0]));
}

// The blocks that moved with an untextured object lie along its outline, inside and out:
// with a depth sensor they pick the object's surface, which the depth then segments whole,
// and place the object frame at the nearer of the two surfaces they hold.
TEST_F(ModellerScene, PixelsThatMovedAlongTheOutlineSelectTheWholeSurface) {
  const RigScene& s = *scene_;
  const PinholeCamera& camera = s.rig.cameras[0].intrinsics;
  const cv::Mat& object = s.object_masks[0];
  cv::Mat outside, inside;
  cv::dilate(object, outside, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(19, 19)));
  cv::erode(object, inside, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(9, 9)));
  const cv::Mat ring = outside & ~inside;
  ASSERT_GT(cv::countNonZero(ring & ~object), cv::countNonZero(ring & object))
      << "the ring must hold more of the wall than of the object";
  const Eigen::Vector3d origin =
      (s.rig.cameras[0].cam_from_world() * s.world_from_obj).translation();
  ModellerOptions options;
  options.depth.source = DepthSourceKind::kSensor;
  const cv::Rect box = cv::boundingRect(ring);
  const PixelRect ring_box{box.x, box.y, box.x + box.width, box.y + box.height};
  auto start_depth = [&](double quantile) {
    options.sensor_mask_depth_quantile = quantile;
    const std::optional<Rigid3d> start =
        Modeller(s.rig, 0, options).InitialPose(s.frame, ring_box, ring, MaskRole::kSelects);
    return start ? (s.rig.cameras[0].cam_from_world() * *start).translation().z() : -1.0;
  };
  EXPECT_NEAR(start_depth(ModellerOptions().sensor_mask_depth_quantile), origin.z(), 0.05);
  EXPECT_GT(start_depth(0.5), 0.9) << "the median lies on the wall 1 m away";
  const std::optional<Rigid3d> bounded_start =
      Modeller(s.rig, 0, options).InitialPose(s.frame, ring_box, ring);  // kBounds: the median
  ASSERT_TRUE(bounded_start.has_value());
  EXPECT_GT((s.rig.cameras[0].cam_from_world() * *bounded_start).translation().z(), 0.9);

  DepthMap map;
  map.depth = s.frame.depths[0];
  map.dense = true;
  const std::optional<PixelRect> sphere = camera.SphereRect(origin, 0.15);
  ASSERT_TRUE(sphere.has_value());
  SegmentationOptions wide;  // a radius that takes in the wall behind the object
  wide.max_radius_m = 0.6;
  wide.remove_support_plane = false;
  const cv::Mat selected =
      SegmentObject(map, camera, *sphere, origin, ring, wide, nullptr, MaskRole::kSelects);
  EXPECT_GT(Iou(selected, object), 0.9);
  const cv::Mat bounded = SegmentObject(map, camera, *sphere, origin, ring, wide);
  EXPECT_LT(Iou(bounded, object), 0.6);
}

TEST_F(ModellerScene, SparseDepthKeepsTheObjectAndDropsWrongMatchesAtItsDepth) {
  const RigScene& s = *scene_;
  const PinholeCamera& camera = s.rig.cameras[0].intrinsics;
  const Eigen::Vector3d origin =
      (s.rig.cameras[0].cam_from_world() * s.world_from_obj).translation();
  // Depth as an image-based source leaves it: every third pixel of the cube, nothing of
  // the wall, and a wrong match at the object's depth beside it (a small blob).
  DepthMap map;
  map.depth = cv::Mat(s.frame.depths[0].size(), CV_32FC1, cv::Scalar(0));
  for (int y = 0; y < map.depth.rows; y += 3) {
    for (int x = 0; x < map.depth.cols; x += 3) {
      if (s.object_masks[0].at<uint8_t>(y, x))
        map.depth.at<float>(y, x) = s.frame.depths[0].at<float>(y, x);
    }
  }
  const cv::Rect box = cv::boundingRect(s.object_masks[0]);
  const cv::Rect blob(box.x - 30, box.y + box.height / 2, 8, 8);
  map.depth(blob).setTo(static_cast<float>(origin.z()));
  SegmentationReport report;
  const cv::Mat mask = SegmentObject(map, camera, ObjectRegion(50), origin, cv::Mat(),
                                     SegmentationOptions(), &report);
  EXPECT_FALSE(report.dense);
  EXPECT_EQ(cv::countNonZero(mask(blob)), 0);
  EXPECT_GT(Iou(mask, s.object_masks[0]), 0.8);
  // Pixels that moved along the object's left edge and over the blob: they select the
  // object's component, whose area reaches beyond them; as a bound they leave a sliver.
  cv::Mat moved = cv::Mat::zeros(mask.size(), CV_8UC1);
  moved(cv::Rect(box.x - 4, box.y, 10, box.height)).setTo(255);
  moved(blob).setTo(255);
  const cv::Mat selected = SegmentObject(map, camera, ObjectRegion(50), origin, moved,
                                         SegmentationOptions(), nullptr, MaskRole::kSelects);
  EXPECT_EQ(cv::countNonZero(selected(blob)), 0);
  EXPECT_GT(Iou(selected, s.object_masks[0]), 0.8);
  EXPECT_LT(Iou(SegmentObject(map, camera, ObjectRegion(50), origin, moved, SegmentationOptions()),
                s.object_masks[0]),
            0.3);
}

TEST_F(ModellerScene, WhatCannotBeModelledIsAStatusNotAnEmptyModel) {
  const RigScene& s = *scene_;
  ModellerOptions options;
  options.depth.source = DepthSourceKind::kPlaneSweep;
  const Modeller modeller(s.rig, 0, options);
  // Behind the camera, or out of its view.
  const Rigid3d behind(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, -1));
  ModelBuild b = modeller.Build(s.frame, behind, PixelRect());
  EXPECT_FALSE(b.ok());
  EXPECT_FALSE(b.why.empty());
  const Rigid3d aside(Eigen::Quaterniond::Identity(), Eigen::Vector3d(3, 0, 0.5));
  b = modeller.Build(s.frame, aside, PixelRect());
  EXPECT_FALSE(b.ok());
  // A region mostly beyond the image's corner: an object cut by the border.
  const PinholeCamera& reference = s.rig.cameras[0].intrinsics;
  b = modeller.Build(s.frame, s.world_from_obj,
                     PixelRect{reference.width - 20, reference.height - 20, reference.width + 40,
                               reference.height + 40});
  EXPECT_FALSE(b.ok());
  EXPECT_NE(b.why.find("image border"), std::string::npos) << b.why;
  // A uniform image: no texture, so no depth from the cameras.
  Frame blank = s.frame;
  for (cv::Mat& im : blank.images) im = cv::Mat(im.size(), CV_32FC3, cv::Scalar(0.5, 0.5, 0.5));
  b = modeller.Build(blank, s.world_from_obj, ObjectRegion(10));
  EXPECT_FALSE(b.ok());
  EXPECT_NE(b.why.find("depth"), std::string::npos) << b.why;
  // Cameras that do not see what the reference sees: no second view to match.
  Rig apart = s.rig;
  for (int c = 1; c < apart.size(); ++c) {
    apart.cameras[c].world_from_cam =
        Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY())),
                Eigen::Vector3d(0.1 * c, 0, 0));
  }
  b = Modeller(apart, 0, options).Build(s.frame, s.world_from_obj, ObjectRegion(10));
  EXPECT_FALSE(b.ok());
  EXPECT_NE(b.why.find("do not overlap"), std::string::npos) << b.why;
  // A mask of the wrong size is an error.
  EXPECT_THROW(
      modeller.Build(s.frame, s.world_from_obj, ObjectRegion(10), cv::Mat::ones(5, 5, CV_8U)),
      Error);
}

TEST(ModellerOptionsYaml, ReadsEverySectionAndNamesWhatIsWrong) {
  const ModellerOptions o = ParseModellerOptions(
      "depth: {source: stereo, max_depth_m: 2.5}\n"
      "stereo: {num_disparities: 64, other_camera: right, search_behind: false}\n"
      "plane_sweep: {planes: 32, disparity_step_px: 1.5}\n"
      "segmentation: {max_radius_m: 0.2, remove_support_plane: false}\n"
      "mesh: {cell_px: 8, contour_vertices: false}\n"
      "model: {origin_offset_m: 0.01}\n",
      "test.yaml");
  EXPECT_EQ(o.depth.source, DepthSourceKind::kStereo);
  EXPECT_EQ(o.depth.max_depth_m, 2.5);
  EXPECT_EQ(o.depth.stereo.num_disparities, 64);
  EXPECT_FALSE(o.depth.stereo.search_behind);
  EXPECT_EQ(o.depth.stereo.other_camera, "right");
  EXPECT_EQ(o.depth.plane_sweep.planes, 32);
  EXPECT_EQ(o.depth.plane_sweep.disparity_step_px, 1.5);
  EXPECT_EQ(o.segmentation.max_radius_m, 0.2);
  EXPECT_FALSE(o.segmentation.remove_support_plane);
  EXPECT_EQ(o.mesh.cell_px, 8);
  EXPECT_FALSE(o.mesh.contour_vertices);
  EXPECT_EQ(o.origin_offset_m, 0.01);
  auto message = [](const std::string& yaml) {
    try {
      ParseModellerOptions(yaml, "bad.yaml");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("depth: {source: lidar}").find("lidar"), std::string::npos);
  EXPECT_NE(message("mesh: {cells: 3}").find("cells"), std::string::npos);
  EXPECT_NE(message("meshes: {}").find("meshes"), std::string::npos);
  EXPECT_NE(message("mesh: {cell_px: 1}").find("cell_px"), std::string::npos);
  EXPECT_NE(message("mesh: {cell_px: many}").find("bad.yaml"), std::string::npos);
  EXPECT_NE(message("plane_sweep: {disparity_step_px: -1}").find("disparity_step_px"),
            std::string::npos);
  EXPECT_NE(message("segmentation: {min_component_share: 1.5}").find("min_component_share"),
            std::string::npos);
  EXPECT_NE(message("segmentation: {min_connected_share: -0.1}")
                .find("segmentation.min_connected_share"),
            std::string::npos);
  EXPECT_NE(message("model: {sensor_mask_depth_quantile: -0.1}").find("sensor_mask_depth"),
            std::string::npos);
  EXPECT_THROW(LoadModellerOptions("/nonexistent/model.yaml"), Error);
}

}  // namespace
}  // namespace unseen
