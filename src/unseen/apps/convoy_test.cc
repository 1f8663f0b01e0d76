// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The convoy simulation: configuration, frames, the rendered view, and a short closed loop
// with unseen's tracker measuring the lead.
#include "unseen/apps/convoy.h"

#include <gtest/gtest.h>

#include <cmath>

#include "unseen/apps/convoy_plot.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

constexpr double kDeg = M_PI / 180.0;

TEST(Convoy, ShippedConfigIsTheThesisRun) {
  const ConvoyOptions o = LoadConvoyOptions("configs/apps/convoy.yaml");
  EXPECT_DOUBLE_EQ(o.vehicle_size_m, 0.055);
  EXPECT_EQ(o.image_width_px, 512);
  EXPECT_EQ(o.image_height_px, 256);
  EXPECT_DOUBLE_EQ(o.controller.separation_m, 0.3);
  EXPECT_DOUBLE_EQ(o.jitter_px_3sigma, 4.0);
  const std::vector<LeadPhase> thesis = ThesisLeadDrive();
  ASSERT_EQ(o.lead_drive.size(), thesis.size());
  for (std::size_t i = 0; i < thesis.size(); ++i) {
    EXPECT_DOUBLE_EQ(o.lead_drive[i].duration_s, thesis[i].duration_s);
    EXPECT_NEAR(o.lead_drive[i].end_speed_m_s, thesis[i].end_speed_m_s, 1e-12);
    EXPECT_NEAR(o.lead_drive[i].yaw_rate_rad_s, thesis[i].yaw_rate_rad_s, 1e-12);
  }
  EXPECT_NEAR(o.frame_interval_s, 1.0 / 30, 1e-12);
  EXPECT_NEAR(o.controller.frame_interval_s, 1.0 / 30, 1e-12);
}

TEST(Convoy, ConfigErrorsNameTheKey) {
  EXPECT_THROW(ParseConvoyOptions("cameras: {}", "t.yaml"), Error);
  EXPECT_THROW(ParseConvoyOptions("camera: {focal: 3}", "t.yaml"), Error);
  EXPECT_THROW(ParseConvoyOptions("render: {supersample: many}", "t.yaml"), Error);
  try {
    ParseConvoyOptions("controller: {separation_mm: 20}", "t.yaml");
    ADD_FAILURE() << "a separation below the vehicle size was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("t.yaml"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ParseConvoyOptions("lead: {phases: [{duration_s: 0}]}", "t.yaml"), Error);
  EXPECT_NO_THROW(ParseConvoyOptions("", "t.yaml"));
}

TEST(Convoy, OptionsCheck) {
  EXPECT_NO_THROW(ConvoyOptions().Check());
  ConvoyOptions o;
  o.supersample = 0;
  EXPECT_THROW(o.Check(), Error);
  o = ConvoyOptions();
  o.lead_drive.clear();
  EXPECT_THROW(o.Check(), Error);
  o = ConvoyOptions();
  o.controller.frame_interval_s = 0.02;  // differs from the frames'
  EXPECT_THROW(o.Check(), Error);
}

TEST(Convoy, PlanarPosesRoundTrip) {
  // Heading +y (forward at the start) is the camera orientation of the world.
  const Rigid3d start = WorldFromPlanar({Eigen::Vector2d(0, 0), M_PI / 2});
  EXPECT_LT(AngleBetween(start.rotation(), Eigen::Quaterniond::Identity()), 1e-12);
  const PlanarPose p{Eigen::Vector2d(0.4, -1.2), 2.5};
  const PlanarPose q = PlanarFromWorld(WorldFromPlanar(p));
  EXPECT_NEAR((q.position - p.position).norm(), 0.0, 1e-12);
  EXPECT_NEAR(WrapAngle(q.heading_rad - p.heading_rad), 0.0, 1e-12);
  // A left turn (heading up) turns the vehicle's forward axis towards the world's -X.
  const Rigid3d left = WorldFromPlanar({Eigen::Vector2d(0, 0), M_PI / 2 + 0.1});
  EXPECT_LT((left.rotation() * Eigen::Vector3d::UnitZ()).x(), 0.0);
}

TEST(Convoy, RendersTheLeadAheadOverTheGround) {
  ConvoyOptions o;
  o.use_tracker = false;
  ConvoySimulation sim(o);
  const Rigid3d cam_from_lead(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 0.3));
  const cv::Mat image = sim.RenderView(Rigid3d(), cam_from_lead);
  ASSERT_EQ(image.size(), cv::Size(512, 256));
  ASSERT_EQ(image.type(), CV_32FC3);
  // The lead covers 55 / 272.5 * 837 = 169 px around the centre; outside it, sky above
  // and ground below the horizon.
  const cv::Vec3f sky = image.at<cv::Vec3f>(10, 10), ground = image.at<cv::Vec3f>(250, 10);
  EXPECT_GT(sky[0], sky[2]);  // blue
  EXPECT_GT(cv::norm(sky - ground), 0.1);
  cv::Scalar mean, dev;
  cv::meanStdDev(image(cv::Rect(200, 70, 112, 112)), mean, dev);
  EXPECT_GT(dev[0] + dev[1] + dev[2], 0.1);  // the textured back face
  EXPECT_GT(cv::norm(image.at<cv::Vec3f>(128, 256) - image.at<cv::Vec3f>(128, 20)), 0.05);
}

TEST(Convoy, ControllerAloneHoldsTheThesisFigures) {
  // No images: the controller measures the rendered (jittered) pose.
  ConvoyOptions o;
  o.use_tracker = false;
  ConvoySimulation sim(o);
  const ConvoyResult r = sim.Run();
  EXPECT_EQ(r.summary.frames, sim.NumFrames());
  EXPECT_GT(r.summary.min_separation_error_m, -0.005);
  EXPECT_LT(r.summary.max_separation_error_m, 0.005);
  EXPECT_LT(r.summary.max_cross_track_m, 0.003);
  // The lead's drive: 90° left then 90° right, ending where it started heading.
  EXPECT_NEAR(WrapAngle(r.frames.back().lead_true.heading_rad - M_PI / 2), 0.0, 1e-6);
  EXPECT_NEAR(r.frames.back().follower.speed_m_s, 0.0, 0.01);
  EXPECT_THROW(sim.Step(), Error);  // all frames done
  const cv::Mat plot = DrawConvoyPlot(r);
  EXPECT_EQ(plot.type(), CV_8UC3);
}

TEST(Convoy, TrackerClosesTheLoop) {
  ConvoyOptions o;  // the thesis run's first 2 s: the lead accelerates to 720 mm/s
  ConvoySimulation sim(o);
  const ConvoyResult r = sim.Run(60);
  ASSERT_EQ(r.frames.size(), 60u);
  for (const ConvoyFrame& f : r.frames) {
    EXPECT_TRUE(f.tracked) << "frame " << f.frame;
    EXPECT_EQ(f.command.measured, f.tracked);
    EXPECT_LT(f.tracking_error_3d_m, 0.002) << "frame " << f.frame;
    EXPECT_LT(std::abs(f.tracking_error_heading_rad), 1.0 * kDeg) << "frame " << f.frame;
    EXPECT_LT(std::abs(f.separation_error_m), 0.005) << "frame " << f.frame;
    EXPECT_LT(f.cross_track_m, 0.003) << "frame " << f.frame;
  }
  EXPECT_EQ(r.summary.tracked, 60);
  // The follower is moving with the lead.
  EXPECT_GT(r.frames.back().follower.speed_m_s, 0.6);
  EXPECT_GT(r.frames.back().follower.pose.position.y(), 0.6);
}

}  // namespace
}  // namespace unseen
