// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The 2-D correlation seeds of the re-acquisition (reacquisition.h; SPEC 3.9 "coarse-level
// 2-D correlation ... to seed the 6-DoF solve"): the model rendered at reference poses is
// located in the input at a coarse pyramid level by normalised cross-correlation of the
// LINF-normalised (4.11), blurred colour or of its gradient magnitude (so a gain or a
// shading ramp does not move the peak); a peak's shift becomes a lateral translation at the
// object's depth. Options: ReacquisitionOptions (tracker_options.h).
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

}  // namespace unseen
