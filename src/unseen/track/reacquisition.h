// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Re-acquisition of a lost object and seeding of motions beyond the pyramid's capture
// range (SPEC 3.9 "Larger motions: coarse-level 2-D correlation ... to seed the 6-DoF
// solve where pyramid levels run out"):
//  * a 2-D correlation seed: the model rendered at a reference pose is located in the input
//    at a coarse level by normalised cross-correlation of gradient magnitudes after LINF
//    (so a gain or a shading ramp does not move the peak); the shift becomes a lateral
//    translation at the object's depth;
//  * candidate start poses while lost: the seeds (of the last good pose and of its turns
//    about the object's centre, each correlated), translations around the last good pose
//    and its turns, bounded in number;
//  * cheap scoring: each candidate is aligned at the coarsest pyramid level(s) only, the
//    best quarter continue one level finer at a time, and only the best one or two are
//    aligned at full resolution.
// Options: ReacquisitionOptions (tracker_options.h).
#pragma once

#include <deque>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/image/template_matching.h"
#include "unseen/mesh/mesh.h"
#include "unseen/track/preprocess.h"
#include "unseen/track/tracker.h"
#include "unseen/track/tracker_options.h"

namespace unseen {

// A start pose found by the 2-D correlation.
struct CorrelationSeed {
  Rigid3d world_from_obj;  // the reference pose translated laterally by the shifts
  double score = 0.0;      // NCC at the peak(s), weighted mean over the cameras used, [-1, 1]
  int level = 0;           // pyramid level of the correlation
  // Per camera, the displacement of the object from where the reference pose puts it,
  // pixels of `level`; NaN for a camera that did not contribute.
  std::vector<Eigen::Vector2d> shift_px;
  double max_shift_px = 0.0;  // largest |shift_px| over the cameras used
  int reference_index = 0;    // which of the reference poses was matched
};

// Templates of the model kept between correlations: while the object is lost, the last
// good pose and its turns are correlated anew in every frame, seen from the same cameras, so
// their renders repeat, and so do their transforms while the background colour they are
// composited over stays about the same. Holds up to kMaxEntries templates of one model.
class CorrelationTemplateCache {
 public:
  static constexpr int kMaxEntries = 32;
  // A template's transforms are reused while the search window's mean colour, which the
  // template is composited over, stays within this of the one they were made with
  // (largest channel difference, intensity in [0, 1]; 0.02: about 5 of 255 grey levels).
  static constexpr double kFillTolerance = 0.02;

  struct Template {
    PinholeCamera camera;
    Rigid3d cam_from_obj;
    // Colour (CV_32FC3) and coverage (CV_32FC1) of the model at cam_from_obj in camera,
    // area-averaged from a 2x2 supersampled render; empty: the model covers no pixel.
    cv::Mat color, coverage;
    // Once matched: the background colour it was composited over and its transforms.
    cv::Scalar fill;
    std::optional<MaskedTemplateMatcher::Prepared> prepared;
  };

  // The model the templates are of; a different one empties the cache.
  void Bind(std::shared_ptr<const Mesh> model);
  const Mesh& model() const { return *model_; }
  // The template of the model at `cam_from_obj` in `camera`, rendered when the same pose
  // and camera were not rendered before. Valid until the next call.
  Template& Find(const PinholeCamera& camera, const Rigid3d& cam_from_obj);
  int hits() const { return hits_; }
  int misses() const { return misses_; }

 private:
  std::shared_ptr<const Mesh> model_;
  std::deque<Template> entries_;  // oldest first
  int hits_ = 0, misses_ = 0;
};

// The pyramid level of the correlation for an object whose bounding sphere is
// `diameter_px` wide at full resolution: the coarsest with at least options.seed_object_px.
int CorrelationLevel(double diameter_px, const ReacquisitionOptions& options);

// Locates the model (bounding sphere `sphere_centre`, `sphere_radius` in the object frame)
// in `images` (one per rig camera, CV_32FC3 in [0, 1], full resolution) within
// options.search_radii bounding-sphere radii of where `reference` puts it. Returns up to
// options.max_seeds seeds with a score of at least options.min_correlation, best first.
//
// Several cameras: each camera's best peak gives the object's lateral displacement at its
// depth in that camera's frame (two equations on the 3-D translation); the equations of
// all cameras, weighted by their peak scores, are solved in least squares with a small
// pull towards no motion, so that the direction no camera sees (the optical axis of a
// single camera) stays as in `reference`. Further seeds come from the next peaks of the
// camera whose best peak scored highest, alone.
std::vector<CorrelationSeed> FindCorrelationSeeds(const std::vector<cv::Mat>& images,
                                                  const Rig& rig, const Mesh& model,
                                                  const Eigen::Vector3d& sphere_centre,
                                                  double sphere_radius, const Rigid3d& reference,
                                                  const ReacquisitionOptions& options,
                                                  const PreprocessOptions& preprocess);
// The same for several orientations of the object about its centre (the first's centre
// sets the level and the search window): the options.max_seeds best seeds over all
// references. An orientation closer to the object's matches it better. With `templates`
// (bound to `model`), the templates' renders come from it when they repeat.
std::vector<CorrelationSeed> FindCorrelationSeeds(
    const std::vector<cv::Mat>& images, const Rig& rig, const Mesh& model,
    const Eigen::Vector3d& sphere_centre, double sphere_radius,
    const std::vector<Rigid3d>& references, const ReacquisitionOptions& options,
    const PreprocessOptions& preprocess, CorrelationTemplateCache* templates = nullptr);

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
