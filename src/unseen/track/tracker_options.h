// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Every setting of the 6-DoF tracker (SPEC 3) in one struct, with the thesis's values as
// defaults, validated once by Check() and loadable from YAML:
//
//   preprocess: {use_linf: true, linf_sigma_px: 8, linf_epsilon: 0.05, blur_sigma_px: 1.8}
//   selection:  {color_mode: redundancy, min_gradient_sq: 984e-6, max_normal_flow_px: 1.22,
//                use_occlusion_rejection: true, block_min_share_ratio: 0.5, ...}
//   solver:     {kernel: huber, kernel_width: 1.345, irls_iterations: 2}
//   pyramid:    {max_levels: 4, min_object_px: 32, max_iterations_per_level: 6,
//                adaptive_levels: true, resample_iterations: 2, rerender_px: 0.5}
//   predictor:  {type: kalman, linear_accel_sigma: 2.0, min_confidence: 0.5}
//   failure:    {lost_confidence: 0.25, lost_after_frames: 2, recover_confidence: 0.5,
//                good_residual_px: 0.5, bad_residual_px: 1.2, min_area_ratio: 0.2, ...}
//   reacquisition: {search_radii: 4, rotation_deg: 25, max_candidates: 12, refine_levels: 2, ...}
//   depth: {...}  region: {...}  live_appearance: {enabled: true, refresh_frames: 1, ...}
//   simplify: {enabled: true, max_normal_angle_rad: 1e-4, relative_tolerance: 1e-5, ...}
//   frame_interval_s: 0.0333
//   threads: 1
#pragma once

#include <string>

#include "unseen/mesh/simplify.h"
#include "unseen/track/depth_modality.h"
#include "unseen/track/flow_solver.h"
#include "unseen/track/live_appearance.h"
#include "unseen/track/motion_predictor.h"
#include "unseen/track/pixel_selection.h"
#include "unseen/track/preprocess.h"
#include "unseen/track/region_modality.h"

namespace unseen {

// Multi-scale alignment (SPEC 3.3) and the Gauss-Newton iterations at each level.
struct PyramidOptions {
  int max_levels = 4;             // cap on pyramid levels (the thesis saw oscillation with more)
  // The coarsest level keeps the object's bounding sphere at least this wide, pixels; so
  // the number of levels follows the object's on-screen size (3.3).
  double min_object_px = 32.0;
  int max_iterations_per_level = 6;  // render-solve-update rounds per level (3.9)
  double min_update_px = 0.1;     // a level is done when an update moves the object less, px
  // Coarser levels (level > 0) only need to bring the pose within the capture range of the
  // next finer level, so they stop earlier: at most this many rounds, and once an update
  // moves the object less than coarse_min_update_px (pixels of that level). Each round
  // costs a render and a pre-processing of the virtual image.
  int coarse_max_iterations = 6;
  double coarse_min_update_px = 0.3;
  // The same while the photometric modality leads (a model with appearance, not demoted;
  // not in the first frame after Initialize, whose checks measure the appearance's drag):
  // the texture's thousands of rows settle a coarse level in a round or two, and an update
  // below a pixel of that level leaves the pose well inside the next level's capture range
  // (textured real cube 6.2 -> 4.7 renders a frame; no accuracy lost on the dev and
  // held-out renders, spider 90 -> 95 %). The silhouette and depth rows alone settle
  // slowly at the coarse levels and need the stricter stop (untextured teapot 100 % at
  // 0.3, 67-82 % at 0.5-1.2).
  double photometric_coarse_min_update_px = 1.0;
  // A tracked frame's coarse level is also done when its solves swing about their optimum:
  // the update turns back on the previous one (negative inner product under the normal
  // matrix, FlowSolution::information) and its squared length under that matrix, which is
  // chi-square distributed with 6 degrees of freedom for an update of noise alone, is below
  // this (3: smaller than 81 % of noise-alone updates; 0: off). A texture's thousands of
  // rows make every update they still give significant (tens to thousands); a silhouette's
  // few hundred leave a weakly held direction in which the solves swung by a pixel for all
  // six rounds of a level. The finest level still runs to min_update_px (stopping it at the
  // noise too cost the untextured CAD engine and rock 10-20 % of rotation accuracy), and a
  // search's alignments run their rounds (the untextured figure was no longer found after a
  // blackout). Without the turn-back condition a noisy update still pointing the right way
  // stopped too (the real cube by its silhouette alone lost 6 frames); at 6 (the
  // distribution's mean) the untextured teapot's slow turn drifted past 5 deg (100 -> 90 %).
  // Measured (--init gt, one thread), rounds a frame: untextured figure behind an occluder
  // 13.5 -> 3.3, 32.5 -> 45 % within 5 cm/5 deg, 12 -> 0 frames lost, 25.0 -> 1.4 mm;
  // untextured glossy figure 3.85 -> 3.76, within 2 cm/2 deg 84 -> 89 %, 1.19 -> 1.10 deg;
  // untextured teapot 6.98 -> 6.03, 2 cm/2 deg 52 -> 62 %, 1.71 -> 1.84 mm, 2.21 -> 2.13 deg;
  // 14 other sequences identical.
  double noise_stop_chi2 = 3.0;
  double max_step_px = 4.0;       // one update moves the object at most this far, level px
  // At the finest level, after a round's solve, up to this many solves of the same rows
  // re-measured at the moved pose (Modality::MoveBy: the photometric modality samples the
  // input anew, the others follow their rows' linear models) before the next render; 0:
  // every solve renders. The level ends when a round's first update is below
  // min_update_px, or when all its solves together moved the object less than rerender_px.
  int resample_iterations = 2;
  double rerender_px = 0.5;
  // Photometric equations nearer the rendered silhouette than this (level pixels) follow
  // their linear model in those solves instead of being measured again.
  int resample_margin_px = 4;
  // Rim around the rendered mask whose pixels give photometric rows, level pixels, in a
  // frame's alignment from the predicted pose (not a search's, which starts far off), for a
  // model whose outline is the object's (not an on-line model's partial surface). Without
  // PreprocessOptions::background_band_px the rim's virtual image is the input itself: its
  // rows match at any pose that keeps them outside and pull towards a smaller model
  // wherever the model's shading differs from the image (0 was as accurate or better than
  // 3 everywhere). With a band of 2 px, a rim of 2 px lets the camera's blur of the
  // silhouette give residuals on both of its sides, which cancel: see background_band_px.
  int rim_px = 0;
  // Levels finer than this are rendered 2x2 supersampled, so that the virtual image has the
  // area-averaged silhouette and texture of a camera image (a point-sampled silhouette pasted
  // over the input biases the pose outwards by about a quarter pixel).
  int supersampled_levels = 8;
  // Pixel budget of the finest level: an object whose rectangle (its bounding box's
  // projection) covers more than max_finest_px pixels of an image at level 0 is aligned
  // no finer than the first level where it covers at most that many; 0: always down to
  // level 0. An object near the camera fills the frame at 10-20 fps at level 0 and is
  // placed as well at level 1, where it is still hundreds of pixels across. A finer level
  // is taken again only once the object fits it within finest_hysteresis of the budget.
  double max_finest_px = 90000.0;
  double finest_hysteresis = 0.7;
  // While tracking, use only as many levels as the expected prediction error needs: the
  // finest level captures about capture_px pixels and each coarser one doubles that; the
  // expected error is prediction_margin times the largest recent correction (a maximum
  // that decays by correction_decay per frame). A doubtful result (confidence below
  // ReacquisitionOptions::doubtful_confidence, or a correction near the reach of the
  // levels used) is redone with the full pyramid. false: always the full pyramid (the
  // thesis).
  bool adaptive_levels = true;
  int min_adaptive_levels = 2;  // but never fewer levels than this (coarse levels smooth the cost)
  double capture_px = 2.0;
  double prediction_margin = 2.0;
  double correction_decay = 0.8;
  void Check() const;
};

// Tracking-failure detection (SPEC 3.9). The confidence of a frame is the product of
//  * the support: the better of the share of rendered-gradient pixels that survive the
//    consistency tests, mapped linearly from [min_share, good_share] to [0, 1], and the
//    absolute number of used pixels, from [min_used_px, good_used_px] to [0, 1] (a partly
//    occluded object whose visible part still gives thousands of equations is supported);
//  * the RMS normal-flow residual before the last update, from [good_residual_px,
//    bad_residual_px] to [1, 0], and its ratio to the residual of the recent confident
//    frames (the noise and model-error floor of this camera and object), from
//    [good_residual_ratio, bad_residual_ratio] to [1, 0]: a misaligned pose keeps fewer
//    but worse-fitting pixels, an occluded but aligned one fits as well as before;
//  * the size of the last update at the finest level (not converged = doubtful), from
//    [good_update_px, bad_update_px] to [1, 0];
// and 0 with fewer than min_pixels equations.
struct FailureOptions {
  double min_share = 0.15;
  double good_share = 0.5;
  double min_used_px = 500;     // used pixels (all cameras)
  double good_used_px = 2500;
  // Behind an occluder (SelectionCounts::occluded_gradient), where the silhouette vouches
  // for the pose (its agreement and residual terms), the share above may count only the
  // visible texture, times the ramp of the visible fraction of the texture from
  // min_visible_fraction to good_visible_fraction and times the silhouette's term; 0
  // disables it.
  double min_visible_fraction = 0.25;
  double good_visible_fraction = 0.5;
  // A camera's image is no render: sensor noise, blur, compression and shading the model
  // lacks leave 0.5-0.6 px of normal-flow residual at the true pose on real footage (0.2-0.4
  // on renders); the ratio to the reference residual below judges a frame against its own
  // camera's floor. (0.3 / 0.9 declared a real RealSense cube lost through its motion-blurred
  // stretch: colour only, 72.7 % within 5 cm/5 deg, 27 frames lost; 100 %, none lost now.)
  double good_residual_px = 0.5;
  double bad_residual_px = 1.2;
  double good_residual_ratio = 1.25;  // residual / reference residual
  double bad_residual_ratio = 1.75;
  // Weight of a new confident frame in the running reference residual (exponential mean),
  // and its floor: below it the fit is at the level of interpolation error, where a
  // doubling means nothing (noiseless renders), px.
  double residual_reference_rate = 0.1;
  double min_reference_residual_px = 0.2;
  // While the silhouette vouches for a confident frame (its agreement at least the region
  // modality's good_agreement, its residual at most vouched_region_residual_ratio times
  // its reference), the photometric reference residual follows at vouched_reference_rate
  // instead: the texture's own floor may rise while the pose stays right (a box whose
  // faces are repeating patterns turning to a slant: 0.31 -> 0.46 px in six frames at
  // 0.2 deg and 2 mm of error), and at the slow rate the tracker declared such an object
  // lost and never found it again (held-out box_checker_fast 41.7 -> 100 %). Without the
  // silhouette's word the slow rate stands, so that an occluder's residual is not learnt.
  // vouched_reference_rate = residual_reference_rate: off.
  double vouched_reference_rate = 0.3;
  double vouched_region_residual_ratio = 1.5;
  // While it vouches, the reference follows a residual up to this times itself (otherwise
  // good_residual_ratio): the same box's floor rose faster than the reference in one frame
  // (0.354 -> 0.401 px against 0.319), was never followed again and the box, at 2 mm, was
  // declared lost (41.7 %; 98.3 % with this). good_residual_ratio: off.
  double vouched_follow_ratio = 1.75;
  double good_update_px = 0.3;
  double bad_update_px = 2.0;
  int min_pixels = 40;
  // The region modality's agreement (RegionModalityOptions) stands in for the photometric
  // terms above when it is higher and rests on at least this many correspondence lines.
  int min_region_lines = 20;
  // The region modality's RMS contour offset (in its standard deviations) against the
  // running mean of the confident frames' (at residual_reference_rate, kept while lost),
  // ramped from [bad_region_residual_ratio, good_region_residual_ratio] to [0, 1], scales
  // what the region modality vouches for: on a wrong pose the silhouette may agree with the
  // learnt colours about as well (a same-coloured occluder) but sits far worse on its
  // contour (2-4x the reference; confident frames stay within 2x).
  double good_region_residual_ratio = 2.0;
  double bad_region_residual_ratio = 3.0;
  // The texture judges a textured model's frames, but not against a silhouette that sits
  // this many times its reference off its contour: the photometric confidence is ramped
  // from 1 at bad_region_residual_ratio to 0 here (on at least min_region_lines lines).
  // Without occlusion rejection, the white bar's frames were re-acquired 0.68 m off at 0.53
  // (a residual of 11.7 standard deviations) and reported tracking for 80 frames (mean
  // error 155 -> 3.1 mm); occluded objects, whose silhouettes are disturbed, stay within
  // it. 0: never.
  double silhouette_veto_ratio = 12.0;
  // Where the photometric selection found an occluder (SelectionCounts::occluded_gradient),
  // that residual is the RMS of this share of the silhouette's lines, those with the
  // smallest offsets: lines across a thin occluder that the texture's blocks missed (legs,
  // rods) are the rest. So also whenever the photometric modality is not in use (no
  // texture to find an occluder with): a look-alike that touches part of the outline
  // (held-out duck, its identical twin passing behind it) runs a few lines on into itself,
  // and over all lines the frame, placed within 0.4 mm, was lost (53 -> 78 % tracked). 1:
  // all lines always.
  double occluded_region_share = 0.9;
  // Floor of that running mean, standard deviations: below it the contour sits within its
  // own noise, where a doubling means nothing (renders without noise, sharp contours).
  double min_reference_region_residual = 1.0;
  // The object's rendered area against the running mean of the confident frames' (at
  // residual_reference_rate): a pose that shows the object far smaller or larger than it has
  // just been is doubtful whatever the modalities say (a solve can settle on a model shrunk
  // to a few dozen pixels far behind the object, all of which fit). The smaller of the
  // ratio and its inverse is ramped from [min_area_ratio, good_area_ratio] to [0, 1].
  // Lost for more than area_memory_frames bad frames in a row, the area is forgotten (the
  // object may really have moved much nearer or farther meanwhile).
  double min_area_ratio = 0.2;
  double good_area_ratio = 0.4;
  int area_memory_frames = 30;
  // The area of an object partly past the image border is its whole silhouette's: the
  // rendered part over the share of the silhouette inside the image (SilhouetteShareInImage,
  // a coarse render of the whole), that share floored at min_in_image_share. An object
  // leaving the view was lost while a fifth of it still showed, its pose right (a box
  // moving out at the right border: 4 mm off, its area ratio 0.2). 1: the part in the
  // image alone.
  double min_in_image_share = 0.1;
  // Measured depth that agrees with the rendered surface almost everywhere vouches, with a
  // silhouette near its contour, for a tracked frame the image modalities doubt: agreeing
  // points (DepthModalityOptions::agree_distance_m) at least depth_vouch_agreement of all
  // measured ones (the hidden counted against it), on at least depth_vouch_min_measured
  // points, and the silhouette's residual at most depth_vouch_max_region_ratio times its
  // reference (on at least min_region_lines lines, and on at least depth_vouch_min_line_share
  // of its lines: a contour the colours tell from its surroundings) hold the confidence at
  // depth_vouch_confidence: the frame stays tracked, doubtful, and cannot re-acquire a lost
  // object (below recover_confidence). A real camera's motion blur leaves the texture and
  // the contour far worse than on the sharp frames their references were learnt from, while
  // the pose is right: the real RGB-D cube at 15 fps lost 9 of 50 frames (82 % within
  // 5 cm/5 deg), with their depth agreeing on 90-97 % of the points; with this 2 (96 %).
  // The silhouette's bound keeps a pose the depth is fooled by out (the cube sunk into the
  // desk, its top face on the desk's plane: 110 mm off, its contour at 10x its residual).
  // 0: off.
  double depth_vouch_agreement = 0.9;
  int depth_vouch_min_measured = 200;
  double depth_vouch_max_region_ratio = 8.0;
  double depth_vouch_min_line_share = 0.5;
  double depth_vouch_confidence = 0.45;
  double lost_confidence = 0.25;   // a frame below this is bad
  int lost_after_frames = 2;       // this many bad frames in a row: lost (hysteresis)
  double recover_confidence = 0.5; // while lost, a frame above this re-acquires
  // ... and, while the texture judges, its share (pixels that pass the consistency tests)
  // is at least this times the running mean share of the confident frames before: a wrong
  // orientation of a look-alike outline (a cube whose faces carry similar letters, back
  // 80 deg turned) passed at confidence 0.78, 48 mm / 59 deg off, with 42 % of its texture
  // agreeing against 97 % while tracked. 0: off.
  double recover_share_ratio = 0.5;
  // While lost, search for the object (ReacquisitionOptions): correlation seeds and poses
  // around the last good one.
  bool search_when_lost = true;
  double search_offset = 0.5;      // translated candidates' step, bounding-sphere radii
  // For this many frames after it was lost, the object is looked for first where its last
  // motion carries it (the motion model runs on uncorrected: an object hidden by an
  // occluder, or in a blur, goes on moving), then held there; the search still turns
  // around the last good pose. 0: held at the last good pose at once.
  int coast_frames = 10;
  void Check() const;
};

// Re-acquisition of a lost object and seeding of motions larger than the pyramid's capture
// range (SPEC 3.9, reacquisition.h). A 2-D correlation seed: the model rendered at a
// reference pose (the last good pose while lost, the predicted one while tracking) is
// matched by normalised cross-correlation of gradient-magnitude images (after LINF) with
// the input at a coarse level, and the best shifts become lateral translations at the
// object's depth. While lost (with failure.search_when_lost), candidate start poses (where
// the motion model coasted, the seeds of the last good pose and of its turns by
// rotation_deg about the object's centre, translations of failure.search_offset radii
// along each world axis, turned poses) are aligned at the coarsest pyramid levels only, a
// few rounds at a time for ever fewer of them; the best quarter continue one level finer
// at a time and the best refine_candidates are aligned at full resolution.
struct ReacquisitionOptions {
  bool use_correlation = true;     // compute the 2-D correlation seed
  // For a model with appearance (Mesh::HasAppearance) whose colours the tracker trusts (its
  // photometric modality in use and not demoted), correlate the LINF-normalised colour
  // (the three channels as one vector) instead of the gradient magnitude: the texture's
  // own pattern rather than its edges' strength, which motion blur and a soft camera take
  // away. A model of one colour, or one whose colours do not fit, keeps the gradient
  // magnitude (its silhouette).
  bool colour_correlation = true;
  // The correlation runs at the coarsest pyramid level where the object's bounding sphere
  // is still at least this wide, pixels of that level.
  double seed_object_px = 24.0;
  // Search window: the object's centre may be this many bounding-sphere radii away from
  // where the reference pose puts it, in each image direction.
  double search_radii = 4.0;
  double min_correlation = 0.3;    // a correlation peak below this (NCC, [-1, 1]) is no seed
  int max_seeds = 4;               // correlation peaks kept as seeds (over all orientations)
  // Rotation candidates: the seeds and the last good pose turned by +-rotation_deg about
  // each world axis through the object's centre, degrees; 0 = none.
  double rotation_deg = 25.0;
  int max_candidates = 12;         // start poses scored per lost frame, in priority order
  // With a pose proposer (Tracker::SetPoseProposer), up to this many of its orientations,
  // placed at the best correlation seed, are scored too (as the seeds are: in every search,
  // quiet or not): an object that comes back into view turned further than rotation_deg.
  int proposals = 4;
  // The coasted pose is scored first; at this coarse confidence or more it is refined at
  // once, and a refinement that re-acquires the object ends the search (the correlation
  // and the other candidates are skipped). > 1: never. (0.99 -> 0.5: the spider behind a
  // sphere, coasted pose at 0.63, is found at once: its search 5.7x -> 2.5-2.8x a tracked
  // frame; the same poses on every development, held-out, occlusion and start run.)
  double accept_coasted_score = 0.5;
  // Besides the coasted pose, score its rotation with the object's centre held at the last
  // good pose (one more candidate). A textured box turning behind a crossing spider: the
  // motion model, corrected by the fading frames before the loss, carried the box 14 cm
  // deeper in 10 frames while it turned in place; found again 7 frames after the loss
  // instead of never (44 -> 87 %).
  bool turn_in_place = true;
  // Candidates are scored by aligning them at this many of the coarsest pyramid levels
  // only (the coarse levels' confidence); the rest of the pyramid is not run for them.
  int score_levels = 1;
  // Render-solve rounds a candidate gets at a time while it is scored (successive halving:
  // all candidates score_iterations rounds, the better half as many more, ..., up to
  // pyramid.coarse_max_iterations) and at each finer level. A candidate near the object is
  // placed in one or two rounds; one far from it moves the full step every round. 6 -> 2
  // with the halving: lost frames 4.5-6x -> 2.7-3.4x the cost of a tracked frame on the
  // held-out occlusion sequences, same poses.
  int score_iterations = 2;
  // Best-scored candidates then aligned at full resolution. Each costs about two tracked
  // frames; the second best never won on the held-out occlusion sequences (2 -> 1: the
  // lost frames of the figure and the spider cost 6x -> 4.5x a tracked frame, same poses).
  int refine_candidates = 1;
  // Pyramid levels of that refinement, the finest ones; 0: the whole pyramid. The scoring
  // already brought the candidate down to level 1, so the coarser levels would repeat it.
  // (0 -> 2, the finest two, measured: lost frames 3.5x -> 3.3x a tracked frame on the
  // held-out figure behind an occluder, 3.1x -> 2.9x on the spider, the figure found a frame
  // earlier; the occluded box without occlusion rejection 81 -> 93 %; the other 43
  // development, held-out and occlusion runs unchanged. 1, level 0 alone, loses the
  // untextured figure after its blackout, where the object turned 60 degrees.)
  int refine_levels = 2;
  double min_score = 0.05;         // a candidate scored below this (confidence) is not refined
  // A search in which no candidate reached min_score says the object is most likely still
  // hidden. The searches after it, while the object stays lost, score the coasted pose,
  // the correlation seeds and only this many of the other candidates (the translations and
  // turns of the last good pose), a different slice in each frame, so that every one of
  // them is tried again within a few frames; a search that scores a candidate at
  // min_score or more makes the next one complete again. -1: every search scores every
  // candidate. (Occluded cube, object hidden for 29 frames: a lost frame 4.7x -> 3x the
  // cost of a tracked frame.)
  int quiet_candidates = 2;
  // While tracking, a frame whose alignment is below doubtful_confidence also tries the
  // correlation seed around the predicted pose (confident frames pay nothing); the seed is
  // aligned only when it moves the object at least min_seed_shift_px, pixels of the
  // correlation level (a smaller shift is within the coarsest level's own reach, and an
  // object that stays doubtful, e.g. a wrong model, would pay a second alignment every
  // frame), and replaces the first alignment only when it reaches
  // failure.recover_confidence and beats it.
  bool seed_when_doubtful = true;
  double doubtful_confidence = 0.5;
  double min_seed_shift_px = 2.0;
  // The seed's window, bounding-sphere radii each way (search_radii while lost): between
  // two tracked frames the object stays near where its motion put it. The seeds that
  // caught fast motion moved it 0.2-0.3 radii (cube_fast_480); one 3.2 radii away, on the
  // real cube's on-line model, aligned at 0.79 and jumped the pose 237 mm while tracking.
  double seed_search_radii = 2.0;
  void Check() const;
};

// The photometric modality (SPEC 3.1): the pre-processing, pixel selection and solver
// settings below are its own; this switches it and weighs it against the others
// (ResidualModel::weight, multiplying 1 / noise^2 with the noise in intensity units).
struct PhotometricOptions {
  bool enabled = true;
  // Only for models with appearance (Mesh::HasAppearance): a model of one flat colour gives
  // the optical flow nothing but its silhouette's edges, which mislead on low-contrast
  // backgrounds and under moving highlights; the region modality judges the silhouette.
  bool require_appearance = true;
  // The first frame after Initialize() checks that the model's appearance fits the image at
  // the given pose: with a photometric fit (Tracker's FailureOptions terms) below this, the
  // model's colours are taken to disagree with the camera's (or to lack its highlights) and
  // the object is tracked without the photometric modality (with region enabled); 0: never.
  double min_start_fit = 0.1;
  // When the first frame's alignment from the given pose (with the checks here) stays below
  // FailureOptions::recover_confidence, it is aligned again: by the silhouette alone from
  // the given pose (a wider basin than the colours'), then jointly from there; the more
  // confident result is kept. A first pose 10 mm and 5 deg off: the held-out textured
  // figure with thin legs 1.7 -> 100 %.
  bool start_by_silhouette = true;
  // The first frame also aligns by the silhouette alone from the given pose: when the joint
  // alignment moves the object more than start_drag_ratio times as far as that one, and
  // more than start_drag_px (level-0 pixels), the model's appearance is taken to pull the
  // pose off (colours shaded unlike the camera's image: a smaller model hides the
  // mismatch) and the object is tracked without the photometric modality; 0: never.
  double start_drag_px = 3.0;
  double start_drag_ratio = 2.0;
  // A model whose appearance drags the first frame's pose is demoted, not dropped: the
  // photometric modality keeps this share of its weight, the silhouette leads and judges
  // the frames (the colours still settle what the silhouette leaves open, such as a spin
  // about an axis of near symmetry). 0: dropped.
  double dragged_weight = 0.1;
  // A demoted model's colours settle only what the silhouette (and depth) leave open: along
  // each direction of the twist its rows count with max(0, 1 - dragged_open_ratio / mu), mu
  // their information there (at dragged_weight) against the other modalities' together
  // (ResidualModel::subordinate_ratio). 0: they count in every direction.
  double dragged_open_ratio = 1.0;
  // Light that changes while tracking (a moving or pulsing lamp; frames without depth):
  // when a tracked frame's photometric fit falls below light_change_fit while the
  // silhouette agrees with the image and sits on its contour (agreement of at least
  // RegionModalityOptions::good_agreement, residual within
  // FailureOptions::good_region_residual_ratio of the confident frames') and the rejected
  // pixels are spread over the object rather than gathered in blocks (RejectionGathering
  // below light_change_max_gathering: an occluder gathers them), the model's shading no
  // longer matches the image: the photometric modality is demoted as above and the frame
  // aligned again. 0: never.
  double light_change_fit = 0.5;
  double light_change_max_gathering = 0.5;
  // A texture that drags the pose off the silhouette while tracking (frames without depth,
  // occlusion rejection on): when a frame's silhouette sits more than silhouette_drag_ratio
  // times its confident frames' residual off its contour (FailureOptions, region residual
  // ratio), the frame is aligned again with the photometric modality demoted as above; that
  // alignment is kept, and the silhouette leads from then on, when its confidence is at
  // least the first's and its contour residual smaller by this ratio again. (A dim textured
  // object in sensor noise: the composed virtual image misreads its blurred outline and the
  // optical flow pulled the pose deeper, 40-230 mm off in six frames before it was lost.)
  // Measured (tracker benchmark, 117 runs of the dev, start, occlusion and held-out groups
  // with 19 held-out renders): dim noisy jeep 21.7 -> 100 % (48.7 -> 4.0 mm), its perturbed
  // start 10 -> 98 %, the box behind the bar demoted at its frame 61 (0.57 -> 0.49 mm); the
  // others unchanged (sum 108.31 -> 109.97). 0: never.
  double silhouette_drag_ratio = 1.5;
  // ... but not while the texture vouches for the pose on more than this share of its
  // pixels (PixelSelection's survival share; the dim jeep's was 0.42), nor while its
  // rejected pixels gather in blocks (RejectionGathering at least light_change_max_gathering:
  // an occluder hiding part of the contour, 0.59-0.66 where the check misfired).
  double silhouette_drag_max_share = 0.8;
  // ... and the realignment led by the silhouette is kept only where its contour residual
  // is at most this many times its confident frames' (the dim jeep 0.85; the box under a
  // circling lamp, whose silhouette the lamp had misled, 1.20-1.92: demoted there, it was
  // tracked 40-180 mm off behind the spider).
  double silhouette_drag_led_ratio = 1.0;
  double weight = 1.0;
  // A model whose colours are projected from camera images onto its own approximate
  // surface (Mesh::projectors: an on-line model's key views, or such a model saved and
  // loaded) carries the surface's error into its texture: a point off the true surface by
  // d along a key view's ray shows its colour about d * sin(turn) aside once the view has
  // turned. Where the frame's measured depth pins the surface, the photometric modality
  // keeps this share of its weight. Measured (--unknown --init gt, sensor depth; mean
  // error): rendered box 0.58 mm / 0.39 deg -> 0.32 / 0.24, cube over clutter 0.49 / 0.27 ->
  // 0.28 / 0.21, glossy duck 96 -> 100 %, jeep behind an occluder 1.56 -> 1.17 deg, untextured
  // teapot 2.60 -> 2.24 deg; the spinning globe 0.61 -> 0.82 deg, the real cube 11.37 ->
  // 11.64 mm. Frames without depth keep the full weight (there the colours hold the depth:
  // at 0.3 the three-camera teapot fell 100 -> 85 %). 1: no change.
  double projected_with_depth_ratio = 0.3;
  void Check() const;
};

struct TrackerOptions {
  PhotometricOptions photometric;
  PreprocessOptions preprocess;
  PixelSelectionOptions selection;
  FlowSolverOptions solver;
  PyramidOptions pyramid;
  MotionPredictorOptions predictor;
  FailureOptions failure;
  ReacquisitionOptions reacquisition;
  DepthModalityOptions depth;    // used when frames carry depth
  RegionModalityOptions region;  // the silhouette against learnt colour statistics
  // Colours from the tracked frames for a model without usable ones of its own.
  LiveAppearanceOptions live_appearance;
  // The given model's flat patches are simplified losslessly before tracking
  // (mesh/simplify.h): a boxy CAD model cut into thousands of triangles renders as fast as
  // its faces need, with the same poses.
  SimplifyOptions simplify;
  double frame_interval_s = 1.0 / 30.0;  // time between frames for the predictor, s
  // Threads for one frame (a ThreadPool): cameras are rendered, pre-processed and
  // selected in parallel; with one camera the input's pre-processing runs beside the first
  // render of a level and the render's shading pass runs in bands of rows. 0: all
  // hardware threads. One by default, the figure the thesis measured.
  int threads = 1;
  void Check() const;
};

// Reads a YAML file of the layout above over the defaults; absent keys keep their default.
// Throws unseen::Error naming the file and the key for an unreadable file, an unknown key,
// a value of the wrong type or one that fails Check().
TrackerOptions LoadTrackerOptions(const std::string& path);
// The same from YAML text; `what` names the source in messages.
TrackerOptions ParseTrackerOptions(const std::string& yaml_text,
                                   const std::string& what = "tracker options");

}  // namespace unseen
