// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/system/system_config.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "unseen/util/error.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

// The message of the unseen::Error `parse` throws ("" when none).
template <typename F>
std::string ErrorOf(F&& parse) {
  try {
    parse();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(SystemConfig, EmptyTextKeepsTheDefaults) {
  const SystemConfig config = ParseSystemConfig("", "empty.yaml");
  const SystemOptions defaults;
  EXPECT_EQ(config.system.regions, defaults.regions);
  EXPECT_EQ(config.system.selection.min_interest_share, defaults.selection.min_interest_share);
  EXPECT_FALSE(config.filters.has_value());
  EXPECT_FALSE(config.modeller.has_value());
}

TEST(SystemConfig, ReadsEverySection) {
  const SystemConfig config = ParseSystemConfig(R"(
system: {regions: interest, reselect_after_lost_frames: 4, rebuild_from_tracked_motion: false}
tracked_motion: {max_difference_px: 2.5}
filters:
  - type: position
    min_m: [-0.1, -0.1, 0.3]
    max_m: [0.1, 0.1, 0.6]
  - type: motion
segmentation: {block_px: 16, remove_dominant_motion: true}
selection: {min_area_px: 300, rank_by_total_interest: false}
known_pose: {max_candidates: 5, rolls: 8, gradient_saturation: 0.5}
update: {mode: periodic, every_frames: 12, refresh_confidence: 0.7, refresh_frames: 3,
         asynchronous: false}
)",
                                                "cfg.yaml");
  EXPECT_EQ(config.system.regions, RegionSource::kInterest);
  EXPECT_EQ(config.system.reselect_after_lost_frames, 4);
  EXPECT_FALSE(config.system.rebuild_from_tracked_motion);
  EXPECT_EQ(config.system.tracked_motion.max_difference_px, 2.5);
  ASSERT_TRUE(config.filters.has_value());
  ASSERT_EQ(config.filters->size(), 2);
  EXPECT_EQ(config.filters->filter(0).name(), "position");
  EXPECT_EQ(config.filters->filter(1).name(), "motion");
  EXPECT_EQ(config.system.segmentation.block_px, 16);
  EXPECT_TRUE(config.system.segmentation.remove_dominant_motion);
  EXPECT_EQ(config.system.selection.min_area_px, 300);
  EXPECT_FALSE(config.system.selection.rank_by_total_interest);
  EXPECT_EQ(config.system.known_pose.max_candidates, 5);
  EXPECT_EQ(config.system.known_pose.views.num_rolls, 8);
  EXPECT_DOUBLE_EQ(config.system.known_pose.views.gradient_saturation, 0.5);
  EXPECT_EQ(config.system.update.mode, ModelUpdateMode::kPeriodic);
  EXPECT_EQ(config.system.update.every_frames, 12);
  EXPECT_DOUBLE_EQ(config.system.update.refresh_confidence, 0.7);
  EXPECT_EQ(config.system.update.refresh_frames, 3);
  EXPECT_FALSE(config.system.update.asynchronous);
}

TEST(SystemConfig, TrackerAndModellerFilesAreRelativeToTheConfiguration) {
  const fs::path dir = fs::temp_directory_path() / "unseen_system_config_test";
  fs::create_directories(dir);
  std::ofstream(dir / "tracker.yaml") << "pyramid: {max_levels: 3}\n";
  std::ofstream(dir / "model.yaml") << "mesh: {cell_px: 20}\n";
  std::ofstream(dir / "system.yaml") << "tracker: tracker.yaml\nmodeller: model.yaml\n";
  const SystemConfig config = LoadSystemConfig((dir / "system.yaml").string());
  EXPECT_EQ(config.tracker.pyramid.max_levels, 3);
  ASSERT_TRUE(config.modeller.has_value());
  EXPECT_EQ(config.modeller->mesh.cell_px, 20);
  fs::remove_all(dir);
}

TEST(SystemConfig, ErrorsNameTheFileTheKeyAndTheValue) {
  auto parse = [](const std::string& text) {
    return ErrorOf([&] { ParseSystemConfig(text, "sys.yaml", "/nonexistent"); });
  };
  std::string e = parse("system: {regions: everywhere}");
  EXPECT_NE(e.find("sys.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("regions"), std::string::npos) << e;
  EXPECT_NE(e.find("everywhere"), std::string::npos) << e;
  e = parse("selection: {min_area_px: lots}");
  EXPECT_NE(e.find("min_area_px"), std::string::npos) << e;
  EXPECT_NE(e.find("lots"), std::string::npos) << e;
  e = parse("trackers: {}");
  EXPECT_NE(e.find("unknown section 'trackers'"), std::string::npos) << e;
  e = parse("update: {mode: sometimes}");
  EXPECT_NE(e.find("sometimes"), std::string::npos) << e;
  e = parse("tracker: missing.yaml");
  EXPECT_NE(e.find("/nonexistent/missing.yaml"), std::string::npos) << e;
  e = parse("system: {reselect_after_lost_frames: 0}");
  EXPECT_NE(e.find("reselect_after_lost_frames"), std::string::npos) << e;
  e = parse("filters: [{type: teleport}]");
  EXPECT_NE(e.find("teleport"), std::string::npos) << e;
  e = parse("tracked_motion: {max_difference_px: -1}");
  EXPECT_NE(e.find("max_difference_px"), std::string::npos) << e;
  e = parse("system: [1, 2");
  EXPECT_NE(e.find("malformed"), std::string::npos) << e;
  EXPECT_NE(ErrorOf([] {
              LoadSystemConfig("/nonexistent/system.yaml");
            }).find("/nonexistent/system.yaml"),
            std::string::npos);
}

// The shipped configurations parse (and stay in step with the options).
TEST(SystemConfig, ShippedConfigurationsLoad) {
  const fs::path dir = fs::path(UNSEEN_SOURCE_DIR) / "configs" / "system";
  int loaded = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".yaml") continue;
    EXPECT_NO_THROW(LoadSystemConfig(entry.path().string())) << entry.path();
    ++loaded;
  }
  EXPECT_GE(loaded, 2);
  const SystemConfig visp = LoadSystemConfig((dir / "visp_rbt_cube.yaml").string());
  EXPECT_EQ(visp.system.regions, RegionSource::kInterest);
  ASSERT_TRUE(visp.filters.has_value());
  EXPECT_EQ(visp.filters->filter(0).name(), "position");
}

}  // namespace
}  // namespace unseen
