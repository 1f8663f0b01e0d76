// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// `unseen eval SEQ POSES`: scores a pose stream (CSV / JSON lines) or a BOP scene_gt.json
// against the sequence's ground truth; prints a table or one JSON object.
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "tools/unseen/commands.h"
#include "unseen/eval/evaluation.h"
#include "unseen/eval/ground_truth_audit.h"
#include "unseen/eval/sequence_poses.h"
#include "unseen/io/sequence.h"
#include "unseen/util/error.h"
#include "unseen/util/files.h"

namespace unseen::cli {
namespace {

struct EvalArgs {
  int obj_id = 0;  // --obj-id; 0: the sequence's own object
  std::string sequence;
  std::string poses;
  std::string bop_camera;
  bool json = false;
  std::string per_frame_csv;
  bool audit_gt = false;
  bool trusted_gt = false;
  GroundTruthAuditOptions audit_options;
  EvaluationOptions options;
};

void RunEval(const EvalArgs& args) {
  namespace fs = std::filesystem;
  UNSEEN_CHECK(Exists(args.sequence), "eval: sequence '{}' does not exist", args.sequence);
  UNSEEN_CHECK(IsFile(args.poses), "eval: pose file '{}' does not exist", args.poses);
  const Sequence sequence = Sequence::Open(args.sequence, args.obj_id);
  std::vector<GroundTruthFrame> ground_truth = SequenceGroundTruth(sequence);
  const std::vector<PoseRecord> poses = ReadPosesForSequence(args.poses, sequence, args.bop_camera);
  std::optional<GroundTruthAudit> audit;
  if (args.audit_gt || args.trusted_gt) {
    audit = AuditGroundTruthWithDepth(sequence, sequence.LoadModel(), args.audit_options);
  }
  if (args.trusted_gt) {
    // Only the frames whose ground truth the measured depth confirms are scored.
    std::map<int, bool> trusted;
    for (size_t i = 0; i < audit->frames.size(); ++i) trusted[audit->frames[i]] = audit->Trusted(i);
    for (GroundTruthFrame& gt : ground_truth) {
      if (!trusted[gt.frame]) gt.world_from_obj.reset();
    }
    UNSEEN_CHECK(audit->trusted > 0, "eval: {}: no frame's ground truth agrees with its depth ({})",
                 args.sequence, audit->Summary());
  }
  const EvaluationResult result = Evaluate(ground_truth, poses, args.options);
  if (!args.per_frame_csv.empty()) WritePerFrameCsv(args.per_frame_csv, result);
  if (args.json) {
    nlohmann::json j = result.ToJson();
    j["sequence"] = args.sequence;
    j["poses"] = args.poses;
    if (audit) {
      j["ground_truth_audit"] = {{"frames", audit->frames},
                                 {"depth_agreement", audit->agreement},
                                 {"judged", audit->judged},
                                 {"trusted", audit->trusted},
                                 {"agree_distance_m", audit->options.agree_distance_m},
                                 {"min_agreement", audit->options.min_agreement},
                                 {"scored_trusted_only", args.trusted_gt}};
    }
    std::printf("%s\n", j.dump().c_str());
  } else {
    std::printf("sequence %s\nposes    %s\n", args.sequence.c_str(), args.poses.c_str());
    if (audit) {
      std::printf("%s%s\n", audit->Summary().c_str(),
                  args.trusted_gt ? "; scoring the trusted frames only" : "");
    }
    std::printf("\n%s", result.Table().c_str());
  }
  std::fflush(stdout);
}

void AddEvalCommand(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* cmd = app.add_subcommand(
      "eval",
      "Score a pose stream (CSV / JSON lines) or a BOP scene_gt.json against the ground truth "
      "of a sequence: position and orientation errors, success at 5 cm/5 deg and 2 cm/2 deg, "
      "lost frames, first failure, fps");
  cmd->add_option("SEQ", args->sequence, "Sequence folder (with ground truth)")->required();
  AddObjectIdOption(cmd, &args->obj_id);
  cmd->add_option("POSES", args->poses, "Pose stream (.csv, .jsonl) or BOP scene_gt.json")
      ->required();
  cmd->add_flag("--json", args->json, "Print one JSON object instead of the table");
  cmd->add_flag("--align-first", args->options.align_first,
                "Remove the offset between the estimated and the true object frame at the "
                "first tracked frame (objects whose frame the system chose)");
  cmd->add_flag("--rot-err-world", args->options.rotation_error_in_world,
                "Per-axis orientation error in the world frame (default: object frame)");
  cmd->add_option("--per-frame", args->per_frame_csv, "Write per-frame errors to this CSV");
  cmd->add_flag("--audit-gt", args->audit_gt,
                "Check the ground truth against the measured depth (RGB-D sequences): the "
                "share of the model's pixels, rendered at the true pose, whose depth agrees");
  cmd->add_flag("--trusted-gt", args->trusted_gt,
                "Score only the frames whose ground truth the measured depth confirms "
                "(implies --audit-gt)");
  cmd->add_option("--gt-agree-mm", args->audit_options.agree_distance_m,
                  "Depth agreement distance of the audit, mm")
      ->transform([](const std::string& mm) { return std::to_string(std::stod(mm) * 1e-3); })
      ->check(CLI::PositiveNumber);
  cmd->add_option("--gt-min-agreement", args->audit_options.min_agreement,
                  "Share of agreeing pixels at which a frame's ground truth is trusted")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--bop-camera", args->bop_camera,
                  "Camera whose frame a BOP scene_gt.json POSES is in (default: the camera "
                  "folder holding it, else the reference camera)");
  cmd->callback([args] { RunEval(*args); });
}

}  // namespace

UNSEEN_REGISTER_COMMAND("eval", AddEvalCommand);

}  // namespace unseen::cli
