// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The 6-DoF tracker (SPEC 3): every frame, predict the pose (3.7), render the model at it
// into every camera inside the bounding-sphere rectangle (3.5), pre-process (3.2), select
// pixels (3.4, 3.6), solve the 6-DoF optical flow of all cameras at once (3.1.1, 3.8) and
// update the pose (4.7), coarse to fine over a pyramid whose depth follows the object's
// on-screen size (3.3) and, while tracking, the size of the recent corrections, several
// render-solve rounds per level with IRLS on top (3.9), at the finest level each round's
// rows solved again at the moved pose before the next render (Modality::MoveBy); then judge
// the result (confidence, status) and re-acquire a lost object (3.9). Cameras, and the stages of one camera, can
// run on several threads (TrackerOptions::threads).
#pragma once

#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/io/sequence.h"
#include "unseen/io/pose_stream.h"
#include "unseen/mesh/mesh.h"
#include "unseen/render/rasterizer.h"
#include "unseen/track/depth_modality.h"
#include "unseen/track/flow_solver.h"
#include "unseen/track/motion_predictor.h"
#include "unseen/track/photometric_modality.h"
#include "unseen/track/pixel_selection.h"
#include "unseen/track/region_modality.h"
#include "unseen/track/preprocess.h"
#include "unseen/track/tracker_options.h"
#include "unseen/util/thread_pool.h"

namespace unseen {

class Reacquisition;

// Wall-clock milliseconds spent in each stage of one frame.
struct StageTimes {
  double predict_ms = 0, render_ms = 0, preprocess_ms = 0, select_ms = 0, solve_ms = 0;
  double total_ms = 0;  // the whole Track() call
  StageTimes& operator+=(const StageTimes& o);
};

// What the alignment of one frame did.
struct SolveSummary {
  int num_levels = 0;                     // pyramid depth: the coarsest level used + 1
  int finest_level = 0;  // the pixel budget's finest level (PyramidOptions::max_finest_px)
  std::vector<int> iterations_per_level;  // solves; index = level (0 = full resolution;
                                          // 0 solves below AlignLevels' finest level)
  int renders = 0;                       // render-solve rounds over all levels
  int noise_stops = 0;  // coarse levels ended by their swing (PyramidOptions::noise_stop_chi2)
  int resamples = 0;                     // solves that re-measured a round's rows instead
  // The object's rendered area in the finest level's last round, all cameras, level-0 px.
  double object_px = 0.0;
  SelectionCounts counts;                // last round at the finest level, all cameras
  int equations = 0;                     // equations of that round
  double initial_residual_px = 0.0;      // RMS normal flow |It|/|grad| before its update
  double final_residual_px = 0.0;        // RMS residual of the linear model after it
  double last_update_px = 0.0;           // image motion of that last update, px
  double correction_px = 0.0;            // image motion of the whole correction this frame
  double share = 0.0;                    // counts.used / counts.gradient_pixels()
  // The depth modality in that round (all zero without depth): its points and the RMS of
  // their point-to-plane distances before the update, metres.
  DepthCounts depth_counts;
  int depth_equations = 0;
  double depth_residual_m = 0.0;
  // The region modality in that round: its lines and the RMS contour offset before the
  // update, standard deviations.
  RegionCounts region_counts;
  double region_residual = 0.0;
  RegionCounts start_region_counts;  // the region modality's first round, at the start pose
  int search_candidates = 0;             // poses tried by the re-acquisition search
  int search_choice = -1;  // the one it returned (0: where the motion model coasted), -1: none
  StageTimes times;
  // One line: levels, iterations, pixels used/rejected, residual, ms.
  std::string BriefReport() const;
};

// Start poses of the model for the object whose silhouette's bounding box in camera
// `camera` (rig index) of `frame` is about `box`: orientations the tracker's own search
// does not reach (the view bank of select/known_model_pose.h). World frame, best first.
using PoseProposer =
    std::function<std::vector<Rigid3d>(const Frame& frame, int camera, const PixelRect& box)>;

struct TrackResult {
  Rigid3d world_from_obj;  // the estimate (the held last good pose while lost)
  TrackStatus status = TrackStatus::kTracking;
  double confidence = 0.0;  // [0, 1]
  SolveSummary summary;
  std::string BriefReport() const;
  // The pose-stream record of this result for frame `frame` at `time_s` (seconds).
  PoseRecord ToPoseRecord(int frame, double time_s,
                          std::optional<double> process_ms = std::nullopt) const;
};

class Tracker {
 public:
  // `rig` gives the cameras (Rig::Check()); `model` the textured mesh in metres, in the
  // object frame (Mesh::Check()); a mesh without texture is rendered with its material or
  // vertex colours. Throws unseen::Error for an invalid rig, model or options.
  Tracker(const Rig& rig, Mesh model, const TrackerOptions& options = {});
  ~Tracker();

  // Replaces the model between frames (e.g. by the on-line modeller); the pose, the motion
  // and the colour statistics of object and surroundings are kept, what was learnt about
  // the old model's fit (residual floor, re-acquisition caches) is reset.
  void SetModel(Mesh model);
  // Starts tracking at `world_from_obj` (metres). Throws for a non-finite pose.
  void Initialize(const Rigid3d& world_from_obj);
  // A pose hint: forget the motion history and the lost state and continue from here.
  void Reset(const Rigid3d& world_from_obj) { Initialize(world_from_obj); }

  // Tracks one synchronized frame: one image per rig camera, in rig order, CV_32FC3 BGR in
  // [0, 1] (CV_8UC3 is converted) of that camera's size, and optionally one depth image
  // per camera (Frame::depths: CV_32FC1 metres, 0 = no measurement, of that camera's size;
  // an empty Mat for a camera without depth), which the depth modality uses
  // (TrackerOptions::depth). An empty colour image means that camera delivered no frame
  // this time: the others are tracked alone (the status and confidence come from them); no
  // image at all is SkipFrame(). Throws unseen::Error before Initialize(), for a wrong
  // number of images or a wrong size/type. An object out of view is reported as lost,
  // never as NaN.
  TrackResult Track(const Frame& frame);
  // The same for colour images alone.
  TrackResult Track(const std::vector<cv::Mat>& images_per_camera);
  // A frame time with no image from any camera (a dropped or unreadable frame). Reported
  // as kLost with the last good pose and confidence 0; the tracking state treats it as a
  // bad frame: the motion predictor moves on by one frame interval, the next frame uses
  // the full pyramid, and FailureOptions::lost_after_frames such frames (or bad ones) in
  // a row make the tracker lost, so that it searches from the last good pose. Throws
  // before Initialize().
  TrackResult SkipFrame();

  // Aligns the model to the frame starting from `world_from_obj` without touching the
  // tracking state (no prediction, no status): the multi-scale render-solve loop and the
  // confidence. `num_levels` > 0 overrides the automatic pyramid depth.
  TrackResult Align(const Frame& frame, const Rigid3d& world_from_obj, int num_levels = 0);
  TrackResult Align(const std::vector<cv::Mat>& images_per_camera, const Rigid3d& world_from_obj,
                    int num_levels = 0);

  // The alignment of `start` on the pyramid levels [finest_level, finest_level +
  // num_levels) only, at most `max_iterations` rounds (renders) per level, as the
  // re-acquisition scores its candidates: nothing is learnt (the region modality judges
  // with the colour statistics of the tracked frames), and the confidence is judged at
  // `finest_level`, in its pixels, without the references learnt at full resolution
  // (on-screen area, residual floors). `frame` at full resolution.
  TrackResult AlignLevels(const Frame& frame, const Rigid3d& start, int finest_level,
                          int num_levels, int max_iterations);

  // Pyramid levels the alignment would use for the object at `world_from_obj`.
  int NumLevelsFor(const Rigid3d& world_from_obj) const;
  // The finest level a tracking alignment of the object at `world_from_obj` runs to
  // (PyramidOptions::max_finest_px, with hysteresis from the last alignment's).
  int FinestLevelFor(const Rigid3d& world_from_obj) const;

  const Rig& rig() const { return rig_; }
  // The model as rendered: the given one or, with LiveAppearanceOptions, the given one with
  // projective textures from the last confidently tracked frame.
  const Mesh& model() const { return *model_; }
  // The same, shared: a Mesh is never changed once rendered (a new appearance is a new
  // Mesh), so a holder of this pointer may cache what it rendered of it.
  std::shared_ptr<const Mesh> shared_model() const { return model_; }
  // The model as given (constructor, SetModel), without live textures.
  const Mesh& given_model() const { return *given_model_; }
  std::shared_ptr<const Mesh> shared_given_model() const { return given_model_; }
  const TrackerOptions& options() const { return options_; }
  const MotionPredictor& predictor() const { return *predictor_; }
  bool initialized() const { return initialized_; }
  TrackStatus status() const { return status_; }
  // The photometric residual of the confident frames that the confidence judges a frame's
  // against (FailureOptions::residual_reference_rate), px; 0 before the first.
  double residual_reference_px() const { return residual_reference_px_; }
  // The texture's share of the confident frames (FailureOptions::recover_share_ratio); 0
  // before the first.
  double share_reference() const { return share_reference_; }
  // Whether the photometric modality runs for the current model (PhotometricOptions:
  // enabled, require_appearance, and the first frame's min_start_fit check).
  bool photometric_in_use() const { return use_photometric_; }
  // Whether it runs demoted (PhotometricOptions::dragged_weight, light_change_fit): at a
  // share of its weight, the silhouette judging the frames.
  bool photometric_demoted() const { return use_photometric_ && photometric_demoted_; }

  // The rectangle of `camera`'s pixels the object can cover at `cam_from_obj`: the
  // bounding sphere's rectangle (3.5, (4.16)-(4.21)) cut down to the projection of the
  // model's box, which is tighter for all but round objects. std::nullopt: out of view.
  std::optional<PixelRect> ObjectRect(const PinholeCamera& camera,
                                      const Rigid3d& cam_from_obj) const;
  // Where a lost frame's search finds the object by correlation (ReacquisitionOptions::
  // proposals), the proposer's orientations there join its candidates; none by default.
  void SetPoseProposer(PoseProposer proposer) { pose_proposer_ = std::move(proposer); }
  const PoseProposer& pose_proposer() const { return pose_proposer_; }

  // The confidence of an alignment: what the modalities vouch for, times the plausibility
  // of the object's on-screen area (FailureOptions::min_area_ratio), judged against what
  // this tracker has learnt so far (residual and area references).
  // `with_references` false: a coarse candidate's (LevelSpan::scoring), without the
  // references learnt at full resolution (area, residual floors).
  double Confidence(const SolveSummary& summary, bool with_references = true) const;

 private:
  struct CameraWork;
  // The frame with colour converted to CV_32FC3 and every image checked against its camera.
  Frame CheckFrame(const Frame& frame) const;
  // Which pyramid levels an alignment runs and how (Align: all from level 0; AlignLevels:
  // a span of coarse levels for scoring).
  struct LevelSpan {
    int finest = 0;          // the level whose result is returned and judged
    int num_levels = 0;      // levels from `finest` up; 0: NumLevelsFor the start pose
    int max_iterations = 0;  // rounds per level at most; 0: PyramidOptions' limits
    bool scoring = false;    // AlignLevels: no learning, confidence without references
    // A frame's alignment from the predicted pose: its coarse levels may also stop at
    // their noise (PyramidOptions::noise_stop_chi2); a search's alignments, which may start
    // far off, run theirs.
    bool tracking = false;
    // The depth rows join every level even while the model's own texture leads (a doubtful
    // frame aligned again: DepthModalityOptions::retry_doubtful_with_coarse_depth).
    bool coarse_depth = false;
  };
  TrackResult AlignChecked(const Frame& frame, const Rigid3d& start, int num_levels,
                           bool tracking = false, bool coarse_depth = false) {
    LevelSpan span;
    span.num_levels = num_levels;
    span.tracking = tracking;
    span.coarse_depth = coarse_depth;
    return AlignChecked(frame, start, span);
  }
  TrackResult AlignChecked(const Frame& frame, const Rigid3d& start, const LevelSpan& span);
  // The alignment of a frame from the predicted pose, with the pyramid depth the recent
  // corrections call for (PyramidOptions::adaptive_levels).
  TrackResult AlignPredicted(const Frame& frame, const Rigid3d& predicted);
  // The first frame after Initialize(): AlignPredicted from the given pose, with the checks
  // that the model's appearance fits the image (PhotometricOptions::min_start_fit,
  // start_drag_px); a model that fails them is tracked without the photometric modality. A
  // model without colours whose silhouette does not confirm the given pose takes the first
  // frame's colours seen from it (LiveAppearanceOptions::when_silhouette_fails).
  // When that stays below FailureOptions::recover_confidence, the frame is aligned again
  // from where the silhouette alone brings the given pose (start_by_silhouette).
  TrackResult AlignFirstFrame(const Frame& frame, const Rigid3d& given);
  // AlignFirstFrame's alignment and checks at the given pose.
  TrackResult AlignFirstFrameAt(const Frame& frame, const Rigid3d& given);
  // What an alignment leaves for the next frames (the region modality's colour statistics,
  // the recent correction): saved before an alternative alignment is tried, restored when
  // that one is not kept.
  struct Learnt {
    std::vector<ColorHistograms> histograms;
    double recent_correction_px = 0.0;
  };
  Learnt SaveLearnt() const { return {region_.histograms(), recent_correction_px_}; }
  void RestoreLearnt(const Learnt& learnt) {
    region_.set_histograms(learnt.histograms);
    recent_correction_px_ = learnt.recent_correction_px;
  }
  double ModalityConfidence(const SolveSummary& summary, bool with_references = true) const;
  // The photometric modality's own judgement of the alignment in [0, 1] (FailureOptions:
  // support, residual, convergence). `silhouette_term` in [0, 1], what the silhouette
  // vouches for, lets the visible texture alone support the pose behind an occluder
  // (FailureOptions::min_visible_fraction); 0: the texture judges by itself.
  double PhotometricFit(const SolveSummary& summary, bool with_references = true,
                        double silhouette_term = 0.0) const;
  // The region modality's residual over the running mean of the confident frames' (with
  // FailureOptions::min_reference_region_residual as its floor); 0 before any.
  double RegionResidualRatio(const SolveSummary& summary) const;
  // Whether the measured depth, with the silhouette on its contour, vouches for a tracked
  // frame (FailureOptions::depth_vouch_agreement).
  bool DepthVouches(const SolveSummary& summary) const;
  // Whether the photometric fit judges the frames (in use and not demoted).
  bool PhotometricJudges() const { return use_photometric_ && !photometric_demoted_; }
  // Whether an alignment's coarse levels leave the depth rows out: the frame carries depth
  // and the model's own texture leads (DepthModalityOptions::coarse_with_own_texture).
  bool CoarseLevelsWithoutDepth(const Frame& frame) const;
  // Whether the rendered outline is the object's, so that the background beside it is
  // estimated and the rim gives photometric rows (PreprocessOptions::background_band_px,
  // PyramidOptions::rim_px): not for a model whose colours were projected from camera
  // images onto its surface (an on-line model, or one saved and loaded), a surface with
  // holes and a partial outline whose outside may be the object itself.
  bool OutlineIsTheObjects() const { return given_model_->projectors.empty(); }
  // Whether a tracked frame's alignment shows the light changed under the model's own
  // colours (PhotometricOptions::light_change_fit); `has_depth`: the frame carries depth.
  bool LightChanged(const SolveSummary& summary, bool has_depth) const;
  // Whether a tracked frame's texture pulled its pose off the silhouette's contour
  // (PhotometricOptions::silhouette_drag_ratio).
  bool TextureDragsSilhouette(const SolveSummary& summary, bool has_depth) const;
  // A lost object's re-acquired pose whose texture agrees far less than it did while
  // tracked (FailureOptions::recover_share_ratio), while the texture judges.
  bool TextureDisowns(const SolveSummary& summary) const;
  // Renders the model into `work`'s region at `cam_from_obj` and composes the virtual image
  // (input with the render over it), its mask and depth; false when nothing was rendered.
  // Touches only `work` (cameras run in parallel).
  // `render_pool` (may be null) runs the render's shading pass.
  bool RenderVirtual(const Rigid3d& cam_from_obj, bool supersample, int level,
                     ThreadPool* render_pool, CameraWork* work) const;
  // RenderVirtual, then the virtual image's pre-processing and the region used (mask and
  // its rim of `rim_px` level pixels) with its depth.
  bool PrepareVirtual(const Rigid3d& cam_from_obj, int level, int rim_px, ThreadPool* render_pool,
                      CameraWork* work) const;
  // fn(0) ... fn(n - 1) on the pool's threads, or in order without a pool.
  void RunParallel(int n, const std::function<void(int)>& fn);
  // Image motion (pixels at `level`, largest over cameras) of the object under `twist`.
  double UpdatePixels(const Rigid3d& world_from_obj, const Vector6d& twist, int level) const;
  // The tracker loses the object at a frame whose prediction was `predicted`: the motion
  // model coasts on from there (FailureOptions::coast_frames).
  void BecomeLost(const Rigid3d& predicted);
  // While lost: the pose the motion model carries the object to this frame, or where it
  // stopped after coast_frames.
  Rigid3d Coast();
  // The re-acquisition search (reacquisition.h), made on first use for the current model.
  Reacquisition& Reacquirer();
  // The photometric modality's use for the given model, from PhotometricOptions and
  // LiveAppearanceOptions; the rendered model becomes the given one.
  void StartWithGivenModel();
  // After a tracked frame: the model takes its colours from it when it lives on the
  // tracked frames' (live_appearance_) and the frame is confident enough.
  void UpdateLiveAppearance(const Frame& frame, const TrackResult& r);
  // The model with `frame`'s colours projected onto it from `world_from_obj` becomes the
  // rendered one (photometric modality on); false when no camera sees it.
  bool TakeLiveAppearance(const Frame& frame, const Rigid3d& world_from_obj);
  // The model with `frame`'s colours projected onto it from `world_from_obj`; null when no
  // camera sees it.
  std::shared_ptr<const Mesh> CaptureLiveAppearance(const Frame& frame,
                                                    const Rigid3d& world_from_obj) const;
  // `live` (a capture) becomes the rendered model.
  void AdoptLiveAppearance(std::shared_ptr<const Mesh> live);
  // A held texture (LiveAppearanceOptions::refresh_frames > 1) that no longer fits this
  // frame (its share fell below refresh_share_ratio of its best): the frame is aligned
  // again with the last tracked frame's colours, which become the held ones.
  bool HeldAppearanceFaded(const TrackResult& r) const;
  // A photometric share below LiveAppearanceOptions::refresh_share_ratio of the held
  // texture's best.
  bool BelowHeldShare(double share) const;
  // The model has no colours of its own, and the silhouette could judge colours taken from
  // the frames (LiveAppearanceOptions).
  bool MayTakeLiveAppearance() const;
  // A model without colours whose first frame, confidently tracked, shows a print over
  // LiveAppearanceOptions::print_share of its surface: the model with that frame's colours
  // (as TakeLiveAppearance captures them); null otherwise.
  std::shared_ptr<const Mesh> PrintSeenAtFirstFrame(const Frame& frame, const TrackResult& r) const;
  // After a tracked frame: whether the model's own colours have fitted so poorly for so
  // long that it should take them from the frames (LiveAppearanceOptions::poor_fit_share).
  bool ColoursNeverFitted(const TrackResult& r);

  Rig rig_;
  std::vector<Rigid3d> cam_from_world_;
  std::shared_ptr<const Mesh> given_model_;  // as given to SetModel()
  // What is rendered: the given model, or it with colours from the tracked frames.
  std::shared_ptr<const Mesh> model_;
  Eigen::Vector3d sphere_centre_ = Eigen::Vector3d::Zero();  // object frame
  double sphere_radius_ = 0.0;
  std::array<Eigen::Vector3d, 8> box_corners_;  // the model's axis-aligned box, object frame
  TrackerOptions options_;
  // The photometric modality runs for this model (PhotometricOptions::require_appearance).
  bool use_photometric_ = true;
  // The model's colours drag the pose or no longer match the light: the photometric
  // modality runs at PhotometricOptions::dragged_weight and the silhouette judges.
  bool photometric_demoted_ = false;
  // Demoted because the first frame found the model's colours dragging its pose: they are
  // still the model's own, and anchor what the silhouette leaves open (a spin), which
  // colours from the frames would let drift; they are kept.
  bool dragged_at_start_ = false;
  // Demoted because the light changed under the model's colours (LightChanged): they are
  // still right in the object frame, only lit otherwise (LiveAppearanceOptions::
  // replace_after_light_change). Set only with photometric_demoted_, which is lifted only
  // with it (StartWithGivenModel) or once colours come from the frames.
  bool demoted_by_light_ = false;
  // The first frame's colours, taken because the silhouette alone could not confirm the
  // given pose, aligned it less confidently than the silhouette (AlignFirstFrameAt).
  bool start_colours_lost_ = false;
  // The model's own colours are not used (none, or the first frame found them misleading):
  // it takes them from the tracked frames (LiveAppearanceOptions).
  bool live_appearance_ = false;
  int frames_since_capture_ = 0;
  double best_live_share_ = 0.0;  // the best photometric share since the last capture
  // The last confident frame's colours while an older capture is held (refresh_frames > 1).
  std::shared_ptr<const Mesh> latest_live_;
  // The model's own colours: the best photometric share of a confident frame since the
  // start, and the confident frames in a row below LiveAppearanceOptions::poor_fit_share.
  double best_share_ = 0.0;
  int poor_fit_frames_ = 0;
  std::unique_ptr<MotionPredictor> predictor_;
  std::unique_ptr<ThreadPool> pool_;  // null with one thread
  std::vector<std::unique_ptr<CameraWork>> work_;
  // The modalities (modality.h), with the current round's equations (reused: their
  // capacity). The region modality's colour statistics are learnt from the level-0 rounds
  // of an alignment and committed when Track() finds the frame confidently tracked.
  PhotometricModality photometric_;
  DepthModality depth_;
  RegionModality region_;
  bool learn_from_start_ = false;  // the next Track() starts at a given pose (Initialize)

  bool initialized_ = false;
  TrackStatus status_ = TrackStatus::kTracking;
  int bad_frames_ = 0;
  Rigid3d last_good_;
  // While lost: where the uncorrected motion model has carried the object, and for how
  // many frames (FailureOptions::coast_frames).
  Rigid3d coast_;
  int coasted_frames_ = 0;
  // Decaying maximum of the recent corrections, level-0 pixels (infinite: unknown).
  double recent_correction_px_ = std::numeric_limits<double>::infinity();
  // The finest level of the last tracking alignment (PyramidOptions::max_finest_px).
  int finest_level_ = 0;
  std::unique_ptr<Reacquisition> reacquisition_;
  PoseProposer pose_proposer_;
  // Running mean of the residual of the confident frames (FailureOptions); 0 = none yet.
  double residual_reference_px_ = 0.0;
  // Running mean of the region modality's residual in the confident frames; 0 = none yet.
  double region_residual_reference_ = 0.0;
  // Running mean of the object's on-screen area in the confident frames, level-0 pixels; 0 = none.
  double area_reference_px_ = 0.0;
  double share_reference_ = 0.0;
};

}  // namespace unseen
