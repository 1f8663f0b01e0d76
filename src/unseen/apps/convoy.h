// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The thesis's convoy-following simulation (SPEC 7.1, [4.5.3-4.5.4]) with unseen's tracker
// closing the loop. Every frame: the lead vehicle (a textured box) is rendered over a
// textured ground plane and a sky from the follower's forward camera at the true relative
// pose plus image jitter; the tracker tracks it; the tracked pose, taken to the world by
// the follower's (exact) odometry, feeds the convoy controller (convoy_controller.h); its
// commands drive the follower's unicycle for one frame interval.
//
// Units: metres and radians here (1 thesis "unit" = 1 mm; configs/apps/convoy.yaml is in
// mm). Frames: the 3-D world has the camera convention (X right, Y down, Z forward at the
// start), the ground is the plane Y = vehicle_size / 2 and vehicle centres move in Y = 0;
// the planar (x, y) of convoy_controller.h is (X, Z). A vehicle's own frame is a camera's
// (x right, y down, z forward); the follower's camera is at its centre, looking forward.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "unseen/apps/convoy_controller.h"
#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/mesh/mesh.h"
#include "unseen/render/rasterizer.h"
#include "unseen/track/tracker.h"

namespace unseen {

// One phase of the lead's drive: the speed ramps linearly to `end_speed_m_s` while it turns
// at `yaw_rate_rad_s` (positive: left).
struct LeadPhase {
  double duration_s = 1.0;
  double end_speed_m_s = 0.0;
  double yaw_rate_rad_s = 0.0;
};

// The thesis run [4.5.4]: to 720 mm/s in 2 s, 1 s straight, a 90° left turn then a 90°
// right turn at 20°/s (radius 2.06 m), 1 s straight, to rest in 2 s.
std::vector<LeadPhase> ThesisLeadDrive();

struct ConvoyOptions {
  double vehicle_size_m = 0.055;  // edge of both (cube) vehicles: 55 units
  int image_width_px = 512;       // the follower's camera [4.5.3]
  int image_height_px = 256;
  double focal_px = 837.3;  // fx = fy, principal point at the centre (34° field)
  double frame_interval_s = 1.0 / 30.0;
  std::vector<LeadPhase> lead_drive = ThesisLeadDrive();
  double settle_s = 1.0;  // simulated time after the lead's drive ends
  // Jitter [4.5.3]: gaussian noise on the lead's position relative to the camera (x, y of
  // the camera frame) before rendering, sized so that 3σ is this many pixels on screen.
  double jitter_px_3sigma = 4.0;
  int supersample = 2;          // renders at this factor and averages down (1: none)
  bool ground = true;           // a textured ground plane (else the sky down to the bottom)
  double ground_tile_m = 0.25;  // the ground texture repeats every this many metres
  uint64_t seed = 1;            // the jitter's and the ground texture's
  // false: no images, no tracker; the controller measures the rendered (jittered) pose.
  bool use_tracker = true;
  ConvoyControllerOptions controller;
  TrackerOptions tracker;
  void Check() const;
};

// Reads configs/apps/convoy.yaml's layout (millimetres, degrees; see that file) over the
// defaults. Throws unseen::Error naming the file, section, key and value.
ConvoyOptions ParseConvoyOptions(const std::string& yaml_text, const std::string& what);
ConvoyOptions LoadConvoyOptions(const std::string& path);

// The planar pose of a vehicle frame given in the 3-D world, and back.
PlanarPose PlanarFromWorld(const Rigid3d& world_from_vehicle);
Rigid3d WorldFromPlanar(const PlanarPose& pose);

// One simulated frame.
struct ConvoyFrame {
  int frame = 0;
  double time_s = 0.0;
  PlanarPose lead_true;      // where the lead is
  PlanarPose lead_rendered;  // where the image shows it (with the jitter)
  PlanarPose lead_tracked;   // what the tracker measured, in the world (held while lost)
  bool tracked = false;      // TrackStatus::kTracking
  double confidence = 0.0;
  VehicleState follower;  // at the frame time, before the command
  ConvoyCommand command;
  // Tracking error against the rendered pose: world x, y (planar) and heading, and the
  // 3-D translation error.
  Eigen::Vector2d tracking_error_m = Eigen::Vector2d::Zero();
  double tracking_error_heading_rad = 0.0;
  double tracking_error_3d_m = 0.0;
  // The same planar error against the true pose (the jitter included in the error).
  Eigen::Vector2d error_to_true_m = Eigen::Vector2d::Zero();
  // Along the lead's true path: the follower's separation minus the set one, and the
  // follower's distance from that path (cross-track error).
  double separation_error_m = 0.0;
  double cross_track_m = 0.0;
  double render_ms = 0.0, track_ms = 0.0;
};

// The run's figures beside the thesis's [4.5.4].
struct ConvoySummary {
  int frames = 0, tracked = 0, lost = 0;
  double rms_tracking_x_m = 0, rms_tracking_y_m = 0, rms_tracking_heading_rad = 0;
  double max_tracking_3d_m = 0;
  double rms_true_x_m = 0, rms_true_y_m = 0;  // against the true (unjittered) pose
  double min_separation_error_m = 0, max_separation_error_m = 0;
  double max_cross_track_m = 0;
  double seconds = 0;  // wall clock of the whole loop
  double frames_per_second = 0;
  double mean_render_ms = 0, mean_track_ms = 0;
  // A table of these against the thesis's figures.
  std::string Report() const;
  nlohmann::json ToJson() const;
};

struct ConvoyResult {
  std::vector<ConvoyFrame> frames;
  std::vector<PlanarPose> lead_path;  // the lead's true path from the follower's start
  ConvoySummary summary;
  nlohmann::json ToJson() const;  // summary and per-frame records (units: m, rad)
};

class ConvoySimulation {
 public:
  // Builds the vehicles, the ground, the camera and (use_tracker) the tracker, initialised
  // at the true first relative pose. Throws unseen::Error for invalid options.
  explicit ConvoySimulation(const ConvoyOptions& options);
  ~ConvoySimulation();

  // Frames until the lead's drive and settle_s have passed.
  int NumFrames() const { return static_cast<int>(lead_states_.size()); }
  bool Done() const { return frame_ >= NumFrames(); }
  // Simulates the next frame. Throws when Done().
  ConvoyFrame Step();
  // Steps `max_frames` frames (<= 0: all) and summarises them; `on_frame` (optional) sees
  // each frame right after its step (last_image() is its image).
  ConvoyResult Run(int max_frames = 0,
                   const std::function<void(const ConvoyFrame&)>& on_frame = nullptr);

  // The follower's camera image of the lead at `cam_from_lead` with the follower at
  // `world_from_cam` (supersampled, CV_32FC3 BGR).
  cv::Mat RenderView(const Rigid3d& world_from_cam, const Rigid3d& cam_from_lead);
  // The last frame's camera image (empty without the tracker).
  const cv::Mat& last_image() const { return last_image_; }
  const PinholeCamera& camera() const { return camera_; }
  const Mesh& lead_model() const { return lead_model_; }

 private:
  // The follower's separation error and cross-track error at `follower`, with the lead at
  // frame `frame` (ConvoyFrame).
  void PathErrors(const Eigen::Vector2d& follower, int frame, double* separation_error_m,
                  double* cross_track_m);

  ConvoyOptions options_;
  PinholeCamera camera_;
  Mesh lead_model_;
  Mesh ground_;
  cv::Mat sky_;                            // supersampled
  std::vector<VehicleState> lead_states_;  // per frame
  std::vector<PlanarPose> lead_path_;      // the follower's start, then lead_states_
  std::vector<double> lead_path_arc_m_;    // arc length along lead_path_
  int path_hint_ = 0;                      // the segment nearest the follower last frame
  std::unique_ptr<Tracker> tracker_;
  ConvoyController controller_;
  VehicleState follower_;
  PlanarPose last_tracked_;
  cv::RNG rng_;
  RenderBuffers buffers_;
  cv::Mat last_image_;
  int frame_ = 0;
};

}  // namespace unseen
