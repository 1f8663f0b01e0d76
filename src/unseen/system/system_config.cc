// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/system/system_config.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "unseen/util/error.h"
#include "unseen/util/files.h"
#include "unseen/util/yaml_options.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

std::string Resolve(const std::string& path, const std::string& base_dir) {
  if (path.empty() || fs::path(path).is_absolute()) return path;
  return (fs::path(base_dir) / path).string();
}

// A file a key names, read through its own loader.
std::string NamedFile(const YAML::Node& node, const std::string& where,
                      const std::string& base_dir) {
  UNSEEN_CHECK(node.IsScalar(), "{}: value '{}' must be a file path", where, YAML::Dump(node));
  const std::string path = Resolve(node.Scalar(), base_dir);
  UNSEEN_CHECK(IsFile(path), "{}: file '{}' not found", where, path);
  return path;
}

YamlSection SystemSection(SystemOptions* o) {
  return {{"regions", YamlEnumField(&o->regions, &ParseRegionSource)},
          {"reselect_after_lost_frames", YamlField(&o->reselect_after_lost_frames)},
          {"rebuild_from_tracked_motion", YamlField(&o->rebuild_from_tracked_motion)},
          {"first_model_from_motion_with_image_depth",
           YamlField(&o->first_model_from_motion_with_image_depth)},
          {"rebuild_min_interest", YamlField(&o->rebuild_min_interest)}};
}

YamlSection TrackedMotionSection(TrackedMotionFilterOptions* o) {
  return {{"max_difference_px", YamlField(&o->max_difference_px)},
          {"relative_difference", YamlField(&o->relative_difference)},
          {"min_object_speed_px", YamlField(&o->min_object_speed_px)}};
}

YamlSection SegmentationSection(MotionSegmentationOptions* o) {
  return {{"block_px", YamlField(&o->block_px)},
          {"min_motion_px", YamlField(&o->min_motion_px)},
          {"max_difference_px", YamlField(&o->max_difference_px)},
          {"relative_difference", YamlField(&o->relative_difference)},
          {"min_blocks", YamlField(&o->min_blocks)},
          {"min_texture", YamlField(&o->min_texture)},
          {"min_interest_share", YamlField(&o->min_interest_share)},
          {"remove_dominant_motion", YamlField(&o->remove_dominant_motion)}};
}

YamlSection SelectionSection(RegionSelectionOptions* o) {
  return {{"min_interest", YamlField(&o->min_interest)},
          {"min_texturedness", YamlField(&o->min_texturedness)},
          {"min_area_px", YamlField(&o->min_area_px)},
          {"min_interest_share", YamlField(&o->min_interest_share)},
          {"min_mean_interest", YamlField(&o->min_mean_interest)},
          {"min_total_interest", YamlField(&o->min_total_interest)},
          {"min_size_m", YamlField(&o->min_size_m)},
          {"max_size_m", YamlField(&o->max_size_m)},
          {"rank_by_total_interest", YamlField(&o->rank_by_total_interest)}};
}

YamlSection KnownPoseSection(KnownModelPoseOptions* o) {
  return {{"directions", YamlField(&o->views.num_directions)},
          {"rolls", YamlField(&o->views.num_rolls)},
          {"patch_px", YamlField(&o->views.patch_px)},
          {"render_px", YamlField(&o->views.render_px)},
          {"silhouette_weight", YamlField(&o->views.silhouette_weight)},
          {"appearance_step", YamlField(&o->views.appearance_step)},
          {"gradient_saturation", YamlField(&o->views.gradient_saturation)},
          {"view_threads", YamlField(&o->views.threads)},
          {"max_candidates", YamlField(&o->max_candidates)},
          {"min_separation_deg", YamlField(&o->min_separation_deg)},
          {"min_confidence", YamlField(&o->min_confidence)},
          {"min_appearance_fit", YamlField(&o->min_appearance_fit)},
          {"min_silhouette_fit", YamlField(&o->min_silhouette_fit)},
          {"min_box_iou", YamlField(&o->min_box_iou)}};
}

YamlSection UpdateSection(ModelUpdateOptions* o) {
  return {{"mode",
           [o](const YAML::Node& node, const std::string& where) {
             UNSEEN_CHECK(node.IsScalar(), "{}: value '{}' is not a string", where,
                          YAML::Dump(node));
             try {
               o->mode = ParseModelUpdateMode(node.Scalar());
             } catch (const Error& e) {
               ThrowError("{}: {}", where, e.what());
             }
           }},
          {"every_frames", YamlField(&o->every_frames)},
          {"min_confidence", YamlField(&o->min_confidence)},
          {"refresh_confidence", YamlField(&o->refresh_confidence)},
          {"refresh_frames", YamlField(&o->refresh_frames)},
          {"refresh_fall_confidence", YamlField(&o->refresh_fall_confidence)},
          {"asynchronous", YamlField(&o->asynchronous)}};
}

}  // namespace

RegionSource ParseRegionSource(const std::string& text, const std::string& where) {
  if (text == "motion") return RegionSource::kMotion;
  if (text == "interest") return RegionSource::kInterest;
  ThrowError("{}: '{}' is not a region source (motion, interest)", where, text);
}

SystemConfig ParseSystemConfig(const std::string& yaml_text, const std::string& what,
                               const std::string& base_dir) {
  const YAML::Node root = ParseYamlText(yaml_text, what);
  SystemConfig config;
  config.source = what;
  if (root.IsNull()) return config;
  UNSEEN_CHECK(root.IsMap(), "{}: expected a map of sections", what);
  const std::map<std::string, YamlSection> sections = {
      {"system", SystemSection(&config.system)},
      {"segmentation", SegmentationSection(&config.system.segmentation)},
      {"selection", SelectionSection(&config.system.selection)},
      {"known_pose", KnownPoseSection(&config.system.known_pose)},
      {"update", UpdateSection(&config.system.update)},
      {"tracked_motion", TrackedMotionSection(&config.system.tracked_motion)}};
  for (const auto& kv : root) {
    const std::string key = YamlKeyName(kv.first, what);
    const std::string where = what + ": " + key;
    if (key == "filters") {
      YAML::Node bank;
      bank["filters"] = kv.second;
      config.filters = ParseInterestFilterBank(YAML::Dump(bank), what, base_dir);
    } else if (key == "tracker") {
      config.tracker = LoadTrackerOptions(NamedFile(kv.second, where, base_dir));
    } else if (key == "modeller") {
      config.modeller = LoadModellerOptions(NamedFile(kv.second, where, base_dir));
    } else if (const auto it = sections.find(key); it != sections.end()) {
      ApplyYamlSection(kv.second, where, it->second);
    } else {
      ThrowError(
          "{}: unknown section '{}' (known: system, filters, segmentation, selection, "
          "known_pose, update, tracked_motion, tracker, modeller)",
          what, key);
    }
  }
  CheckOptionsFrom(config.system, what);
  return config;
}

SystemConfig LoadSystemConfig(const std::string& path) {
  UNSEEN_CHECK(IsFile(path), "{}: cannot read the system configuration file", path);
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  UNSEEN_CHECK(in.good() || in.eof(), "{}: cannot read the system configuration file", path);
  const fs::path folder = fs::path(path).parent_path();
  return ParseSystemConfig(text.str(), path, folder.empty() ? "." : folder.string());
}

}  // namespace unseen
