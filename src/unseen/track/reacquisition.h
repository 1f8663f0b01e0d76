// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Re-acquisition of a lost object and seeding of motions beyond the pyramid's capture
// range (SPEC 3.9 "Larger motions: coarse-level 2-D correlation ... to seed the 6-DoF
// solve where pyramid levels run out"):
//  * a 2-D correlation seed (correlation_seeds.h): the model rendered at a reference pose
//    is located in the input at a coarse level by normalised cross-correlation; the shift
//    becomes a lateral translation at the object's depth;
//  * candidate start poses while lost: the seeds (of the last good pose and of its turns
//    about the object's centre, each correlated), translations around the last good pose
//    and its turns, bounded in number;
//  * cheap scoring: each candidate is aligned at the coarsest pyramid level(s) only, the
//    best quarter continue one level finer at a time, and only the best one or two are
//    aligned at full resolution.
// Options: ReacquisitionOptions (tracker_options.h).
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/mesh/mesh.h"
#include "unseen/track/correlation_seeds.h"
#include "unseen/track/preprocess.h"
#include "unseen/track/tracker.h"
#include "unseen/track/tracker_options.h"

namespace unseen {

// `pose` turned by `rotation` (world frame) about the object's point `centre_in_obj`,
// which stays where it is.
Rigid3d RotatedAboutPoint(const Rigid3d& world_from_obj, const Eigen::Quaterniond& rotation,
                          const Eigen::Vector3d& centre_in_obj);

// `world_from_obj` turned by +-angle_deg about each world axis through the object's point
// `centre_in_obj`: six poses (none for angle_deg <= 0).
std::vector<Rigid3d> TurnedAboutCentre(const Rigid3d& world_from_obj,
                                       const Eigen::Vector3d& centre_in_obj, double angle_deg);

// Start poses to try while lost, most promising first, at most options.max_candidates:
// the seeds in their order, the translations of `last_good` by +-translation_step_m along
// each world axis (twice that along z), the rotations of `last_good` and then those of
// the best seed by options.rotation_deg. `last_good` itself is not included.
std::vector<Rigid3d> ReacquisitionCandidates(const Rigid3d& last_good,
                                             const std::vector<CorrelationSeed>& seeds,
                                             const Eigen::Vector3d& sphere_centre,
                                             double translation_step_m,
                                             const ReacquisitionOptions& options);

// Re-acquisition for one Tracker: scores candidates with the tracker's own aligner at the
// coarse levels (Tracker::AlignLevels) and refines the best at full resolution
// (Tracker::Align). Uses only the tracker's public interface.
class Reacquisition {
 public:
  // `tracker` must outlive this; its model and options are read at construction (make a
  // new Reacquisition after Tracker::SetModel).
  explicit Reacquisition(Tracker* tracker);
  ~Reacquisition();

  // `frame` is checked (Tracker::CheckFrame); its depth, if any, serves the full-resolution
  // alignments.
  // While lost: correlates `last_good` and its turns, scores `coasted` (where the motion
  // model carries the object), its turn with the object's centre held at `last_good`
  // (ReacquisitionOptions::turn_in_place) and the candidates around `last_good` at the
  // coarse levels (successive halving down to level 1), aligns the best
  // options.refine_candidates at full resolution (stopping once one reaches
  // failure.recover_confidence) and returns the most confident of them (confidence 0 at
  // `coasted` when none was refined; summary.search_candidates = poses tried, times
  // summed). After a search that found nothing, the next ones of the same loss are quiet
  // (options.quiet_candidates).
  TrackResult Search(const Frame& frame, const Rigid3d& last_good, const Rigid3d& coasted);
  // While tracking, for a doubtful frame: `first` is the full alignment from `predicted`.
  // Aligns from the correlation seed around `predicted` when it moves the object, and
  // returns that alignment when it is at least failure.recover_confidence and more
  // confident than `first` (`*from_seed` then true), else `first`.
  TrackResult Seed(const Frame& frame, const Rigid3d& predicted, TrackResult first,
                   bool* from_seed);

  // The alignment of `start` at the coarsest options.score_levels levels of the pyramid
  // the tracker would use at `start`, the confidence from the finest of those levels
  // (in its pixels); `images` at full resolution. The pose is in metres as usual.
  TrackResult ScoreCoarse(const std::vector<cv::Mat>& images, const Rigid3d& start);

  const Eigen::Vector3d& sphere_centre() const { return sphere_centre_; }
  double sphere_radius() const { return sphere_radius_; }

 private:
  // The tracker's reacquisition options, the colour correlation only while its photometric
  // modality is in use and not demoted.
  ReacquisitionOptions CorrelationOptions() const;
  // The tracker's pose proposer's orientations (ReacquisitionOptions::proposals) for the
  // object where `seed` puts it; none without a proposer or a camera that sees it.
  std::vector<Rigid3d> Proposals(const Frame& frame, const CorrelationSeed& seed) const;
  // The tracker's alignment of `start` on the pyramid levels [finest, finest + num_levels)
  // of `images` (full resolution), score_iterations rounds per level
  // (Tracker::AlignLevels); the full alignment when `finest` is 0.
  TrackResult AlignCoarse(const std::vector<cv::Mat>& images, int finest, int num_levels,
                          const Rigid3d& start);

  Tracker& tracker_;
  CorrelationTemplateCache templates_;
  // Quiet searches (ReacquisitionOptions::quiet_candidates): the last good pose of the
  // loss being searched, whether its last search found nothing, and the next slice of the
  // candidates around the last good pose.
  std::optional<Rigid3d> quiet_last_good_;
  bool quiet_ = false;
  int quiet_slice_ = 0;
  Eigen::Vector3d sphere_centre_ = Eigen::Vector3d::Zero();
  double sphere_radius_ = 0.0;
};

}  // namespace unseen
