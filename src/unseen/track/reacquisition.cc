// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/track/reacquisition.h"

#include <algorithm>
#include <cmath>

#include "unseen/util/error.h"
#include "unseen/util/logging.h"
#include "unseen/util/timer.h"

namespace unseen {

std::vector<Rigid3d> TurnedAboutCentre(const Rigid3d& world_from_obj,
                                       const Eigen::Vector3d& centre_in_obj, double angle_deg) {
  std::vector<Rigid3d> out;
  if (angle_deg <= 0.0) return out;
  const double angle = angle_deg * M_PI / 180.0;
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {-1.0, 1.0}) {
      out.push_back(RotatedAboutPoint(
          world_from_obj, ExpSO3(sign * angle * Eigen::Vector3d::Unit(axis)), centre_in_obj));
    }
  }
  return out;
}

Rigid3d RotatedAboutPoint(const Rigid3d& world_from_obj, const Eigen::Quaterniond& rotation,
                          const Eigen::Vector3d& centre_in_obj) {
  const Eigen::Vector3d centre = world_from_obj * centre_in_obj;
  const Eigen::Quaterniond turned = rotation * world_from_obj.rotation();
  return Rigid3d(turned, centre - turned * centre_in_obj);
}

std::vector<Rigid3d> ReacquisitionCandidates(const Rigid3d& last_good,
                                             const std::vector<CorrelationSeed>& seeds,
                                             const Eigen::Vector3d& sphere_centre,
                                             double translation_step_m,
                                             const ReacquisitionOptions& options) {
  std::vector<Rigid3d> out;
  auto add = [&](const Rigid3d& pose) {
    if (static_cast<int>(out.size()) < options.max_candidates) out.push_back(pose);
  };
  for (const CorrelationSeed& s : seeds) add(s.world_from_obj);
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {-1.0, 1.0}) {
      const Eigen::Vector3d offset =
          sign * translation_step_m * (axis == 2 ? 2.0 : 1.0) * Eigen::Vector3d::Unit(axis);
      add(Rigid3d(last_good.rotation(), last_good.translation() + offset));
    }
  }
  for (const Rigid3d& p : TurnedAboutCentre(last_good, sphere_centre, options.rotation_deg)) {
    add(p);
  }
  if (!seeds.empty()) {
    for (const Rigid3d& p :
         TurnedAboutCentre(seeds[0].world_from_obj, sphere_centre, options.rotation_deg)) {
      add(p);
    }
  }
  return out;
}

Reacquisition::Reacquisition(Tracker* tracker) : tracker_(*tracker) {
  Eigen::Vector3f centre;
  float radius = 0.0f;
  tracker_.model().BoundingSphere(&centre, &radius);
  sphere_centre_ = centre.cast<double>();
  sphere_radius_ = radius;
}

std::vector<Rigid3d> Reacquisition::Proposals(const Frame& frame, const CorrelationSeed& seed) const {
  const PoseProposer& proposer = tracker_.pose_proposer();
  const int wanted = tracker_.options().reacquisition.proposals;
  if (!proposer || wanted <= 0) return {};
  // The object's box where the seed puts it (Tracker::ObjectRect), in the camera that sees
  // it largest (the proposer takes its longer side).
  const Rig& rig = tracker_.rig();
  int camera = -1;
  PixelRect box;
  for (int c = 0; c < rig.size(); ++c) {
    if (c >= static_cast<int>(frame.images.size()) || frame.images[c].empty() ||
        !seed.shift_px[c].allFinite()) {
      continue;
    }
    const std::optional<PixelRect> rect = tracker_.ObjectRect(
        rig.cameras[c].intrinsics, rig.cameras[c].cam_from_world() * seed.world_from_obj);
    if (!rect || rect->width() < 8 || rect->height() < 8) continue;
    if (camera < 0 || rect->width() * rect->height() > box.width() * box.height()) {
      camera = c;
      box = *rect;
    }
  }
  if (camera < 0) return {};
  // Each proposal's orientation, about the object's centre where the seed puts it.
  const Eigen::Vector3d centre = seed.world_from_obj * sphere_centre_;
  std::vector<Rigid3d> out;
  for (const Rigid3d& p : proposer(frame, camera, box)) {
    if (static_cast<int>(out.size()) >= wanted) break;
    out.emplace_back(p.rotation(), centre - p.rotation() * sphere_centre_);
  }
  return out;
}

Reacquisition::~Reacquisition() = default;

TrackResult Reacquisition::AlignCoarse(const std::vector<cv::Mat>& images, int finest,
                                       int num_levels, const Rigid3d& start) {
  // Colour alone, as the correlation that found the candidates: measured depth serves the
  // full-resolution refinement.
  if (finest == 0) return tracker_.Align(images, start, num_levels);
  const TrackerOptions& options = tracker_.options();
  Frame frame;
  frame.images = images;
  return tracker_.AlignLevels(
      frame, start, finest, num_levels,
      std::min(options.pyramid.coarse_max_iterations, options.reacquisition.score_iterations));
}

TrackResult Reacquisition::ScoreCoarse(const std::vector<cv::Mat>& images,
                                       const Rigid3d& start) {
  const int levels = tracker_.NumLevelsFor(start);
  const int finest = std::max(0, levels - tracker_.options().reacquisition.score_levels);
  return AlignCoarse(images, finest, levels - finest, start);
}

ReacquisitionOptions Reacquisition::CorrelationOptions() const {
  // Colour correlates only while the model's colours are trusted: not when they were found
  // not to fit the images and the silhouette leads (their pattern then finds look-alikes as
  // readily as the object: a weakly textured duck behind a textured spider).
  ReacquisitionOptions o = tracker_.options().reacquisition;
  o.colour_correlation =
      o.colour_correlation && tracker_.photometric_in_use() && !tracker_.photometric_demoted();
  return o;
}

TrackResult Reacquisition::Search(const Frame& frame, const Rigid3d& last_good,
                                  const Rigid3d& coasted) {
  const std::vector<cv::Mat>& images = frame.images;
  const TrackerOptions& options = tracker_.options();
  const ReacquisitionOptions& o = options.reacquisition;
  StageTimes times;
  // The coasted pose is scored first: an object that comes out from behind an occluder is
  // most likely where it went on moving. When it scores at least accept_coasted_score at
  // the coarse levels, it is refined at once and, if that re-acquires the object, the
  // search ends there (no correlation, no other candidate).
  const int levels = tracker_.NumLevelsFor(last_good);
  const int finest = std::max(0, levels - o.score_levels);
  TrackResult coasted_scored = AlignCoarse(images, finest, levels - finest, coasted);
  times += coasted_scored.summary.times;
  if (finest > 0 && coasted_scored.world_from_obj.IsValid() &&
      coasted_scored.confidence >= o.accept_coasted_score) {
    TrackResult r = tracker_.Align(frame, coasted_scored.world_from_obj, levels);
    times += r.summary.times;
    UNSEEN_LOG_DEBUG("coasted pose: coarse conf {:.2f}, refined conf {:.2f} at {}",
                     coasted_scored.confidence, r.confidence, r.world_from_obj.ToString());
    if (r.world_from_obj.IsValid() && r.confidence >= options.failure.recover_confidence) {
      r.summary.times = times;
      r.summary.search_candidates = 1;
      r.summary.search_choice = 0;
      return r;
    }
  }
  Timer timer;
  std::vector<CorrelationSeed> seeds;
  if (o.use_correlation) {
    // The last good pose and its rotations, each located by correlation.
    std::vector<Rigid3d> orientations{last_good};
    for (const Rigid3d& p : TurnedAboutCentre(last_good, sphere_centre_, o.rotation_deg)) {
      orientations.push_back(p);
    }
    // The same last good pose in every lost frame: its templates are rendered once.
    templates_.Bind(tracker_.shared_model());
    seeds = FindCorrelationSeeds(images, tracker_.rig(), templates_.model(), sphere_centre_,
                                 sphere_radius_, orientations, CorrelationOptions(),
                                 options.preprocess, &templates_);
  }
  const double correlation_ms = timer.ElapsedMilliseconds();
  times.preprocess_ms += correlation_ms;
  UNSEEN_LOG_DEBUG("correlation: {} seeds in {:.1f} ms (template renders reused {}, made {})",
                   seeds.size(), correlation_ms, templates_.hits(), templates_.misses());
  for (const CorrelationSeed& seed : seeds) {
    UNSEEN_LOG_DEBUG("correlation seed: shift {:.1f} px at level {}, ncc {:.2f}: {}",
                     seed.max_shift_px, seed.level, seed.score, seed.world_from_obj.ToString());
  }
  // The coasted pose first: an object that comes out from behind an occluder is most
  // likely where it went on moving.
  std::vector<Rigid3d> candidates{coasted};
  // Then the coasted turn with the object's centre held where it was last seen: a hand
  // that turns an object behind an occluder goes on turning it, while the extrapolated
  // translation (weakest in depth, and learnt from the fading frames before the loss) may
  // run away. Not when the two are a fraction of a search step apart.
  const double step_m = options.failure.search_offset * sphere_radius_;
  if (o.turn_in_place) {
    const Rigid3d turned = RotatedAboutPoint(
        last_good, coasted.rotation() * last_good.rotation().inverse(), sphere_centre_);
    if ((turned.translation() - coasted.translation()).norm() > 0.25 * step_m) {
      candidates.push_back(turned);
    }
  }
  const std::vector<Rigid3d> around =
      ReacquisitionCandidates(last_good, seeds, sphere_centre_, step_m, o);
  // A new loss (another last good pose) starts with a complete search.
  if (!quiet_last_good_ || !(quiet_last_good_->translation() == last_good.translation() &&
                             quiet_last_good_->rotation().coeffs() ==
                                 last_good.rotation().coeffs())) {
    quiet_ = false;
    quiet_slice_ = 0;
  }
  quiet_last_good_ = last_good;
  const int num_seeds = std::min(static_cast<int>(seeds.size()), static_cast<int>(around.size()));
  const int num_others = static_cast<int>(around.size()) - num_seeds;
  // The seeds, the proposer's orientations at the best of them, then the others.
  candidates.insert(candidates.end(), around.begin(), around.begin() + num_seeds);
  if (!seeds.empty()) {
    const std::vector<Rigid3d> proposed = Proposals(frame, seeds[0]);
    candidates.insert(candidates.end(), proposed.begin(), proposed.end());
  }
  if (quiet_ && o.quiet_candidates >= 0 && o.quiet_candidates < num_others) {
    // The object was not seen in the last search: a slice of the others.
    for (int k = 0; k < o.quiet_candidates; ++k) {
      candidates.push_back(around[num_seeds + (quiet_slice_ * o.quiet_candidates + k) % num_others]);
    }
    ++quiet_slice_;
  } else {
    candidates.insert(candidates.end(), around.begin() + num_seeds, around.end());
  }

  // Score every candidate at the coarse levels (the full pyramid when it has no more); the
  // coasted pose's score is the one above.
  // Candidates that score alike below min_score (most often 0: still converging, the last
  // update too long for any confidence) are ranked by how much of the image already agrees
  // with them: the share of the texture's pixels used plus the silhouette's agreeing share
  // (a candidate 10 deg from a box back in view: 0.60 + 0.77, its 11 companions at most
  // 0.31 + 0.74). Ranked in the order they were made, the successive halving below kept
  // the first of them and dropped that box's one good candidate, frame after frame.
  struct Scored {
    double score;
    Rigid3d pose;
    int order;
    double promise = 0.0;
  };
  auto promise = [](const SolveSummary& s) {
    return s.share + std::max(s.region_counts.Agreement(), 0.0);
  };
  std::vector<Scored> scored;
  TrackResult best;  // nothing found yet
  best.world_from_obj = coasted;
  int choice = -1;  // the candidate `best` came from
  for (int i = 0; i < static_cast<int>(candidates.size()); ++i) {
    TrackResult c = i == 0 ? std::move(coasted_scored)
                           : AlignCoarse(images, finest, levels - finest, candidates[i]);
    if (i > 0) times += c.summary.times;
    if (!c.world_from_obj.IsValid()) continue;
    if (finest == 0) {  // already aligned at full resolution
      if (c.confidence > best.confidence) {
        best = std::move(c);
        choice = i;
      }
      continue;
    }
    UNSEEN_LOG_DEBUG("candidate {}: coarse conf {:.2f} at {}", i, c.confidence,
                     c.world_from_obj.ToString());
    scored.push_back({c.confidence, c.world_from_obj, i, promise(c.summary)});
  }
  auto by_score = [&o](const Scored& a, const Scored& b) {
    if (a.score != b.score) return a.score > b.score;
    if (a.score < o.min_score && a.promise != b.promise) return a.promise > b.promise;
    return a.order < b.order;  // equally confident: the more likely kind first
  };
  std::sort(scored.begin(), scored.end(), by_score);
  // Nothing like the object at any candidate: the next search, if the object stays lost,
  // is a quiet one.
  quiet_ = finest == 0 ? best.confidence < o.min_score
                       : scored.empty() || scored.front().score < o.min_score;
  // Aligns candidate `c` on from where it stopped (`num_levels` from `level`); false (the
  // candidate as it was) when that gave no valid pose.
  auto continue_one = [&](Scored* c, int level, int num_levels) {
    TrackResult r = AlignCoarse(images, level, num_levels, c->pose);
    times += r.summary.times;
    UNSEEN_LOG_DEBUG("candidate {} at level {}: conf {:.2f} at {}", c->order, level, r.confidence,
                     r.world_from_obj.ToString());
    if (!r.world_from_obj.IsValid()) return false;
    c->score = r.confidence;
    c->promise = promise(r.summary);
    c->pose = r.world_from_obj;
    return true;
  };
  // The same for every scored candidate, sorted again.
  auto continue_scored = [&](int level, int num_levels) {
    for (Scored& c : scored) continue_one(&c, level, num_levels);
    std::sort(scored.begin(), scored.end(), by_score);
  };
  // Successive halving in rounds at the scoring level: each candidate had score_iterations
  // rounds; the better half, at least refine_candidates, as many more from where they
  // stopped, and so on up to the coarse levels' own limit. A candidate that needs a long
  // way (a turn the candidates missed) is continued while it looks promising; the hopeless
  // stop early.
  const int round_limit = std::max(options.pyramid.coarse_max_iterations, o.score_iterations);
  for (int rounds = o.score_iterations; rounds + o.score_iterations <= round_limit;
       rounds += o.score_iterations) {
    const int keep = std::max(o.refine_candidates, (static_cast<int>(scored.size()) + 1) / 2);
    if (keep >= static_cast<int>(scored.size()) && rounds > o.score_iterations) break;
    if (keep < static_cast<int>(scored.size())) scored.resize(keep);
    continue_scored(finest, levels - finest);
  }
  // Successive halving down the pyramid: at each finer level (but the finest) a quarter of
  // the survivors, at least refine_candidates, continue from where they converged; the
  // finer level tells orientations apart that the coarse silhouette does not. A survivor
  // that falls below min_score there gives its place to the next best, up to twice as many
  // tried: a look-alike (a textured occluder, a background pattern) can outscore the object
  // at the coarse level and only the finer one tells them apart.
  for (int level = finest - 1; level >= 1; --level) {
    const int keep = std::max(o.refine_candidates, (static_cast<int>(scored.size()) + 3) / 4);
    std::vector<Scored> survivors;
    int found = 0;
    for (int k = 0; k < static_cast<int>(scored.size()) && k < 2 * keep && found < keep; ++k) {
      Scored c = scored[k];
      if (c.score < o.min_score) break;
      if (!continue_one(&c, level, 1)) continue;
      if (c.score >= o.min_score) ++found;
      survivors.push_back(c);
    }
    scored = std::move(survivors);
    std::sort(scored.begin(), scored.end(), by_score);
  }
  UNSEEN_LOG_DEBUG("scored {} candidates in {:.1f} ms", candidates.size(),
                   timer.ElapsedMilliseconds() - correlation_ms);
  // The best refine_candidates are refined; one whose refinement collapses (below
  // min_score: the coarse levels took a look-alike for the object) gives its place to the
  // next, once.
  int refinements = o.refine_candidates;
  for (int k = 0; k < static_cast<int>(scored.size()) && k < refinements; ++k) {
    if (best.confidence >= options.failure.recover_confidence) break;
    if (scored[k].score < o.min_score) break;
    TrackResult r = tracker_.Align(frame, scored[k].pose, std::min(o.refine_levels, levels));
    times += r.summary.times;
    UNSEEN_LOG_DEBUG("refined candidate {}: conf {:.2f} at {}", scored[k].order, r.confidence,
                     r.world_from_obj.ToString());
    if (r.confidence < o.min_score && refinements == o.refine_candidates) ++refinements;
    if (r.confidence > best.confidence) {
      best = std::move(r);
      choice = scored[k].order;
    }
  }
  best.summary.times = times;
  best.summary.search_candidates = static_cast<int>(candidates.size());
  best.summary.search_choice = choice;
  return best;
}

TrackResult Reacquisition::Seed(const Frame& frame, const Rigid3d& predicted, TrackResult first,
                                bool* from_seed) {
  const std::vector<cv::Mat>& images = frame.images;
  const TrackerOptions& options = tracker_.options();
  const ReacquisitionOptions& o = options.reacquisition;
  *from_seed = false;
  if (!o.use_correlation) return first;
  StageTimes times = first.summary.times;
  Timer timer;
  ReacquisitionOptions seeding = CorrelationOptions();
  seeding.search_radii = o.seed_search_radii;  // the object is near where its motion put it
  const std::vector<CorrelationSeed> seeds =
      FindCorrelationSeeds(images, tracker_.rig(), tracker_.model(), sphere_centre_,
                           sphere_radius_, predicted, seeding, options.preprocess);
  times.preprocess_ms += timer.ElapsedMilliseconds();
  TrackResult best = std::move(first);
  if (!seeds.empty() && seeds[0].max_shift_px >= o.min_seed_shift_px) {
    TrackResult r = tracker_.Align(frame, seeds[0].world_from_obj);
    times += r.summary.times;
    UNSEEN_LOG_DEBUG("correlation seed: shift {:.1f} px at level {}, ncc {:.2f}: conf {:.2f} "
                     "(first {:.2f})",
                     seeds[0].max_shift_px, seeds[0].level, seeds[0].score, r.confidence,
                     best.confidence);
    // A jump needs the evidence of a re-acquisition: a marginal pose far away is more
    // likely a look-alike than the object.
    if (r.confidence >= options.failure.recover_confidence && r.confidence > best.confidence) {
      best = std::move(r);
      *from_seed = true;
    }
    best.summary.search_candidates = 2;
  }
  best.summary.times = times;
  return best;
}

}  // namespace unseen
