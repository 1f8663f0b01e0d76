// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The initial pose of a known model, automatically (SPEC 4.5, thesis 2.2.2): given the
// object's bounding box in one camera's image (from the selection, or a user), the views
// of the model that best match the box's square (view_bank.h) give start poses — the
// orientation of the view, the position from the box's centre and size — and the tracker
// tracks the frame from each (every camera, every modality) and judges it. Of the
// alignments confident enough, the one whose appearance fits the image best is the pose;
// with none, "no pose" is the answer, not a guess, and the caller tries another frame or
// region. Beyond the thesis:
// in-plane rotations, the silhouette cue, several candidates verified by the tracker.
#pragma once

#include <atomic>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include "unseen/camera/camera.h"
#include "unseen/geometry/rigid3.h"
#include "unseen/io/sequence.h"
#include "unseen/select/view_bank.h"
#include "unseen/track/tracker.h"

namespace unseen {

struct KnownModelPoseOptions {
  ViewBankOptions views;
  int max_candidates = 12;           // views turned into start poses, best score first
  double min_separation_deg = 20.0;  // between the orientations of two candidates
  // An alignment below this tracker confidence is not a pose (FailureOptions'
  // recover_confidence is the same judgement for re-acquisition).
  double min_confidence = 0.5;
  // ... and below this fit (KnownModelPoseResult::fit) neither: a wrong orientation leaves
  // most of the texture disagreeing with the image (measured on the development
  // sequences from their true boxes: right 0.3-0.9, one real-cube start at 0.19; wrong
  // poses from a region covering part of the object: 0.20-0.21). A model without
  // appearance has only its silhouette's agreement: 0.90-0.95 when aligned from the true
  // pose (the untextured figure), 0.64-0.86 at the wrong orientations its views gave (the
  // figure, a mug); a near-symmetric rock passes at 0.96 turned, which no threshold stops.
  double min_appearance_fit = 0.25;
  double min_silhouette_fit = 0.9;
  // ... nor an alignment whose silhouette's bounding box overlaps the given box by less
  // than this intersection over union: the tracker may have pulled a start poorly placed
  // by a wrong box onto something else (metres away, a few pixels wide).
  double min_box_iou = 0.5;
  void Check() const;
};

struct KnownModelPoseResult {
  bool found = false;
  Rigid3d world_from_obj;   // the most confident alignment (also when not `found`)
  double confidence = 0.0;  // the tracker's, [0, 1]
  // What ranked it among the confident candidates: the share of the model's textured
  // pixels the image agrees with (SolveSummary::share), or, for a model without
  // appearance, the silhouette's agreement.
  double fit = 0.0;
  double box_iou = 0.0;  // of its silhouette's box with the given box
  int candidate = -1;    // which candidate it came from (0: the best-matching view)
  int candidates_aligned = 0;
  TrackResult tracked;    // the tracker's result for the frame from the chosen candidate
  double match_ms = 0.0;  // scoring the views
  double align_ms = 0.0;  // tracking the frame from the candidates
  std::string BriefReport() const;
};

class KnownModelPoser {
 public:
  // Renders the views of `tracker`'s model (which must outlive this, as must `tracker`).
  // Throws unseen::Error for invalid options.
  KnownModelPoser(Tracker* tracker, const KnownModelPoseOptions& options = {});
  // The same with the views of `tracker`'s given model already rendered (options.views
  // as they were rendered with).
  KnownModelPoser(Tracker* tracker, ViewBank views, const KnownModelPoseOptions& options = {});

  // The object whose silhouette's bounding box in camera `camera` (rig index) of `frame`
  // is `box`. Each candidate is tracked in `frame` from scratch (Tracker::Initialize, then
  // Track); when a pose is found the tracker is initialised at it (Tracker::Initialize), so
  // tracking goes on with the next frame (otherwise initialise it before tracking).
  // Throws unseen::Error for a camera index out of range, an empty box or a frame the
  // tracker cannot use.
  KnownModelPoseResult Find(const Frame& frame, int camera, const PixelRect& box);

  // The start poses Find would try, best first (for inspection and tests).
  std::vector<Rigid3d> Candidates(const Frame& frame, int camera, const PixelRect& box) const;

  const ViewBank& views() const { return views_; }

 private:
  Tracker& tracker_;
  KnownModelPoseOptions options_;
  ViewBank views_;
};

// The bounding box of `model` seen by `camera` at `cam_from_obj` (its rendered
// silhouette), or an empty rectangle when it covers no pixel: the box a perfect
// selection would give (benchmarks and tests).
PixelRect SilhouetteBox(const Mesh& model, const PinholeCamera& camera,
                        const Rigid3d& cam_from_obj);

// A pose proposer for `tracker`'s re-acquisition (Tracker::SetPoseProposer): the start poses
// of a KnownModelPoser of its given model (KnownModelPoser::Candidates). The default bank's
// 4 800 views take 1.1 s on one core, 0.53 s on two (ViewBankOptions::threads; 8 in-plane
// turns instead of 16 halve that, but then the lettered cube's true orientation was not
// among the first four proposals). `tracker` must outlive it (held by the tracker itself,
// it does); the views are those of the model the tracker was given when the proposer was
// made. No proposals (empty) when the views cannot be made.
//
// When the proposer's views are rendered:
enum class ViewBankBuild {
  // At the first call. A tracker that never loses its object pays nothing; one that does
  // stalls for that long at its first loss.
  kAtFirstUse,
  // At once, beside tracking, on threads of their own (ViewBankOptions::threads) at the
  // lowest priority, so that tracking keeps its speed. The first call takes them if they
  // are done; if not, it cancels them and renders them itself, as kAtFirstUse (never a
  // longer stall than that, whatever else keeps the machine busy). The same proposals,
  // and no stall once the first loss comes after the render (the command line's choice).
  kInBackground,
};
PoseProposer ViewBankProposer(Tracker* tracker, const KnownModelPoseOptions& options = {},
                              ViewBankBuild build = ViewBankBuild::kAtFirstUse);

// kInBackground's render: the views of `model` rendered at once on threads of their own
// (ViewBankOptions::threads) at the lowest priority. Destroying it cancels the render and
// waits for its threads.
class BackgroundViewBank {
 public:
  BackgroundViewBank(std::shared_ptr<const Mesh> model, const ViewBankOptions& options);
  ~BackgroundViewBank();
  BackgroundViewBank(const BackgroundViewBank&) = delete;
  BackgroundViewBank& operator=(const BackgroundViewBank&) = delete;

  // The views if they are rendered, once; otherwise (not done yet: the render is
  // cancelled; cancelled, failed, taken before) null.
  std::shared_ptr<ViewBank> TakeIfDone();
  // Until the render has ended (tests, tools).
  void Wait() const;

 private:
  std::atomic<bool> cancel_{false};
  std::future<std::shared_ptr<ViewBank>> done_;
};

// The proposer with the views `background` renders, taken at the first call if done
// (rendered then as with kAtFirstUse if not, or if `background` is null).
PoseProposer ViewBankProposer(Tracker* tracker, const KnownModelPoseOptions& options,
                              std::shared_ptr<BackgroundViewBank> background);

}  // namespace unseen
