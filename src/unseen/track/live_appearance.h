// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Appearance from the live image (SPEC 5.3 applied to tracking): a model with no colours
// of its own, or whose colours the first frame found misleading (PhotometricOptions'
// start checks), takes them from the confidently tracked frames by projective texturing.
// Each camera's frame, cropped to the object's rectangle at the tracked pose, becomes a
// projector fixed to the object, with the model's depth seen from it so that surfaces it
// did not see fall back to the model's own colours. The photometric modality then
// compares each new frame with the object as it looked a moment ago, under the same light
// and camera response, while the silhouette (and measured depth) keep it anchored to the
// model's shape.
#pragma once

#include <optional>

#include <opencv2/core.hpp>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/mesh/mesh.h"

namespace unseen {

struct LiveAppearanceOptions {
  // Off by default, by measurement: on a matte CAD model with wrong part colours it halves
  // the error (held-out engine: 5.1 -> 1.9 mm) and the time, but on glossy objects the
  // highlights baked into the texture move over the surface and the pose drifts (held-out
  // duck and the untextured figure fall from 100 % to 35-63 %).
  bool enabled = false;
  // With enabled: every model takes its colours from the frames, also one whose own
  // colours fit. For light that changes strongly while the object is tracked (a moving
  // lamp: held-out small box, 47 -> 100 %); elsewhere the model's own colours anchor the
  // pose better (occluded box, cluttered cube: a few mm of drift, or loss).
  bool always = false;
  // Frames tracked at least this confidently give the model its colours.
  double min_confidence = 0.8;
  // A model without colours of its own whose silhouette alone cannot confirm the given pose
  // (the first frame aligned by it below min_confidence: an object coloured like its
  // surroundings, a white cube on white paper) takes its colours from the frames, whatever
  // `enabled` says, starting with the first frame's seen from the given pose, when that
  // aligns the first frame more confidently (or when too many of its lines ran on:
  // first_overrun_share). Real footage with untextured models: a printed cube on white paper
  // 4 -> 212 of 218 frames tracked (218 with first_overrun_share), a castle with depth 1 -> 30
  // of 30.
  bool when_silhouette_fails = true;
  // With when_silhouette_fails: the silhouette alone does not confirm the given pose either
  // when more than this share of the first frame's contour lines run on past their end
  // (left out of its alignment, RegionModalityOptions::skip_overrun_lines): around much of
  // the object the image is coloured like it, and the lines left confirm too little (a
  // printed cube on white paper, 0.29 of its lines: by its silhouette alone confidence 1.00
  // on the rest, lost at frame 211 of 218; with the frames' colours 218 of 218). The
  // frame's colours are then kept unless they align it less confidently (or below
  // min_confidence). Only while those lines are left out (skip_overrun_lines). The renders of
  // the tracker benchmark's first frames reach at most 0.08. 1: never.
  double first_overrun_share = 0.2;
  // A model without colours of its own takes them from the frames, whatever `enabled`
  // says, when its first frame, tracked at min_confidence or more, shows a print on at least
  // print_share of it: pixels print_inset_px or more inside its outline whose grey level
  // changes by print_min_gradient (of [0, 1]) or more per pixel (TexturedShare). A printed
  // cube given as a bare CAD cube (0.21 of it) tracks by the print 1.76 -> 0.43 deg and
  // 91 -> 100 %, while the untextured objects the frames' colours mislead stay on their
  // silhouette: a matte teapot (0.04) fell 100 -> 8 %, a low-contrast mug's starts to 5 %
  // with them (the glossy figure, 0.08, would have gained). > 1: never.
  // With several cameras, the largest share any of them sees. Not after the first frame's
  // colours aligned it less confidently than its silhouette (when_silhouette_fails).
  double print_share = 0.12;
  // Grey-level change per pixel, of [0, 1], that counts as print (20 of 255 levels).
  double print_min_gradient = 0.08;
  // Pixels this close to the outline are not judged (the silhouette's own edge).
  int print_inset_px = 3;
  // A texture is held for at most this many frames, then taken again. Taken every frame, it
  // follows the light and the view best but the pose walks with it: an untextured figure
  // turned 0.9 -> 8 deg away over 40 frames (45 % tracked); held, it stays within 1.6 deg
  // (100 %), and glossy or lamp-lit objects gain too (held-out opera house 2.6 -> 0.9 mm).
  int refresh_frames = 40;
  // A held texture is taken again early once a confident frame's photometric share falls
  // below this ratio of its best since it was taken (the view or the light moved on). A
  // frame it no longer fits (below that share, or a doubtful confidence) is aligned again
  // with the last confident frame's colours, which become the held ones: under fast motion
  // a texture some frames old can fail at once (a real printed cube: share 0.79 -> 0.20 in
  // one frame). 0: only after refresh_frames.
  double refresh_share_ratio = 0.7;
  // Pixels around the object's rectangle kept in the projector's image.
  int margin_px = 2;
  // A point farther from the projector than the surface it saw by more than this share of
  // the model's bounding radius was hidden from it (self-occlusion).
  double occlusion_tolerance = 0.05;
  // The photometric modality's weight (PhotometricOptions::weight) while the colours come
  // from the frames. Low: frame to frame, the optical flow cannot see a slow drift (in
  // depth above all) nor tell a highlight that moved over a glossy surface from the surface
  // moving; the silhouette must keep the upper hand, the colours settle what it leaves open.
  double photometric_weight = 0.1;
  // Colours that never fitted, whatever `enabled` says: a model tracked confidently
  // (confidence >= poor_fit_confidence, by the silhouette or measured depth) whose colours
  // kept less than poor_fit_share of the rendered-gradient pixels (the photometric share of
  // SolveSummary) for poor_fit_frames tracked frames in a row, and never more than
  // poor_fit_best_share since the start, takes its colours from the frames. (Models lit
  // like their renders keep 0.56-0.90 of their pixels; a real camera's cube at best 0.54,
  // a textured model under a circling lamp 0.39.) A frame whose rejected pixels gather in
  // blocks (SelectionCounts::RejectionGathering at least
  // PhotometricOptions::light_change_max_gathering) shows an occluder, not the colours: it
  // is not counted, and the frames after it go on counting (a textured box under a lamp,
  // best 0.51, falls to 0.31 with 0.6-0.7 of its rejections gathered while something
  // crosses in front; the real cube's poor frames gather 0.38-0.43). 0 frames: never.
  double poor_fit_share = 0.4;
  int poor_fit_frames = 5;
  double poor_fit_best_share = 0.6;
  double poor_fit_confidence = 0.5;
  // Whether colours that never fitted are replaced after the tracker demoted them because
  // the light changed under them (PhotometricOptions::light_change_fit). false: they are
  // kept, at the demoted weight: still right in the object frame, they settle what the
  // silhouette leaves open, while colours taken from the frames follow the tracked pose and
  // cannot hold a spin the silhouette does not see (the red blobs under a moving lamp from
  // a start 4 deg off turned 48 deg with them; the glossy duck's third start 58 -> 100 %).
  // Colours demoted for dragging the silhouette are replaced either way (a real camera's
  // cube without its depth needs the frames' colours).
  bool replace_after_light_change = false;
  void Check() const;
};

// The projector of one camera's frame: `image` (CV_32FC3, the camera's full frame) inside
// `rect` (pixels of `camera`, clipped to the image), with the depth of `model` rendered
// at `cam_from_obj` over the same pixels and the object-frame pose of the camera.
// std::nullopt when the rectangle is empty or the model covers none of it.
std::optional<Projector> CaptureProjector(const Mesh& model, const PinholeCamera& camera,
                                          const Rigid3d& cam_from_obj, const cv::Mat& image,
                                          const PixelRect& rect, float depth_tolerance_m);

// Share of the pixels the projector saw the model cover, `inset_px` or more inside its
// outline, where the image's grey level changes by at least `min_gradient` per pixel (of
// [0, 1]): how much of the surface shows a print; -1 when it covers none. (Grey-level steps
// on the projector's crop; the modeller's Texturedness, a module above this one, sums the
// colour channels' squared gradients over whole images.)
double TexturedShare(const Projector& p, double min_gradient, int inset_px);

}  // namespace unseen
