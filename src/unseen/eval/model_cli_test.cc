// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// End-to-end tests of `unseen model` and `unseen track --unknown` on a short synthetic RGB-D
// sequence, running the built binary (UNSEEN_CLI): an object without a model file is
// modelled and tracked, the model can be saved and tracked as a known one, and what cannot
// work fails clearly.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "unseen/eval/cli_testing.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

std::string TempPath(const std::string& name) {
  return testing::CliTempPath("model_cli_test", name);
}

testing::CliResult RunCli(const std::string& args) {
  return testing::RunCli("model_cli_test", args);
}

// Share of frames within 5 cm / 5 deg, from `unseen eval --json`.
double Success(const std::string& sequence, const std::string& poses,
               const std::string& flags = "") {
  const testing::CliResult r =
      RunCli(fmt::format("eval '{}' '{}' --json {}", sequence, poses, flags));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out).at("success_5cm5deg").get<double>();
}

// The README demo scene's first 20 frames (the cube over clutter) with depth images.
class ModelCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(TempPath("seq"));
    fs::remove_all(*dir_);
    const testing::CliResult r = RunCli(fmt::format(
        "-q synth '{}/scenes/demo.yaml' '{}' --frames 20 --depth", UNSEEN_SOURCE_DIR, *dir_));
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  static std::string* dir_;
};
std::string* ModelCli::dir_ = nullptr;

TEST_F(ModelCli, BuildsAModelThatTracksAsAKnownOne) {
  const std::string model = TempPath("built/cube.ply"), debug = TempPath("debug");
  fs::remove_all(TempPath("built"));
  fs::remove_all(debug);
  const testing::CliResult built = RunCli(
      fmt::format("model '{}' --frame 0 --init gt --depth sensor --out '{}' --debug-dir '{}'",
                  *dir_, model, debug));
  ASSERT_EQ(built.exit_code, 0) << built.err;
  EXPECT_NE(built.out.find("triangles"), std::string::npos) << built.out;
  EXPECT_NE(built.out.find("track --init"), std::string::npos) << built.out;
  EXPECT_TRUE(fs::exists(model));
  EXPECT_TRUE(fs::exists(TempPath("built/cube_projectors.json")));
  for (const char* image : {"depth.png", "texturedness.png", "mask.png", "mesh_overlay.png"}) {
    EXPECT_TRUE(fs::exists(fs::path(debug) / image)) << image;
  }
  const std::string poses = TempPath("known.csv");
  const testing::CliResult tracked =
      RunCli(fmt::format("-q track '{}' --model '{}' --init gt --out '{}'", *dir_, model, poses));
  ASSERT_EQ(tracked.exit_code, 0) << tracked.err;
  EXPECT_GE(Success(*dir_, poses), 0.95);
}

TEST_F(ModelCli, TracksAnUnknownObjectFromItsRegionOrTheTruth) {
  // The cube's box in the first frame (512x256 image).
  for (const std::string where : {"--init gt", "--roi 147,74,114,113"}) {
    const std::string poses = TempPath("unknown.csv"), saved = TempPath("saved/final.ply");
    fs::remove_all(TempPath("saved"));
    const testing::CliResult r = RunCli(
        fmt::format("-q track '{}' --unknown {} --update-frames 5 --out '{}' --save-model '{}'",
                    *dir_, where, poses, saved));
    ASSERT_EQ(r.exit_code, 0) << where << ": " << r.err;
    EXPECT_NE(r.out.find("on-line model"), std::string::npos) << r.out;
    EXPECT_TRUE(fs::exists(saved)) << where;
    // In the true object frame the poses are scored as they are; from a region the frame is
    // the system's own (SPEC 4.4), scored after --align-first.
    EXPECT_GE(Success(*dir_, poses, where == "--init gt" ? "" : "--align-first"), 0.95) << where;
  }
}

TEST_F(ModelCli, AFusedModelGrowsAndTracksTheSequenceFromTheStart) {
  const std::string poses = TempPath("fused.csv"), saved = TempPath("fused/model.ply");
  fs::remove_all(TempPath("fused"));
  const testing::CliResult r =
      RunCli(fmt::format("-q track '{}' --unknown --init gt --update incremental --update-frames 5 "
                         "--update-in-frame --out '{}' --save-model '{}'",
                         *dir_, poses, saved));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("fused model:"), std::string::npos) << r.out;
  EXPECT_GE(Success(*dir_, poses), 0.95);
  // The saved model, its key views' images and the depth they saw, tracks as a given one.
  EXPECT_TRUE(fs::exists(TempPath("fused/model_projectors.json")));
  EXPECT_TRUE(fs::exists(TempPath("fused/model_projector_000_depth.png")));
  const std::string again = TempPath("fused_again.csv");
  const testing::CliResult tracked = RunCli(fmt::format(
      "-q track '{}' --model '{}' --model-units mm --init gt --out '{}'", *dir_, saved, again));
  ASSERT_EQ(tracked.exit_code, 0) << tracked.err;
  EXPECT_GE(Success(*dir_, again), 0.95);
}

TEST_F(ModelCli, WhatCannotWorkFailsClearly) {
  struct Case {
    std::string args, message;
  };
  const std::string seq = "'" + *dir_ + "'";
  for (const Case& c : {
           Case{"track " + seq + " --unknown", "say where the object is"},
           Case{"track " + seq + " --unknown --init gt --model x.ply", "exclude each other"},
           Case{"track " + seq + " --unknown --roi 1,2,3", "four numbers"},
           Case{"track " + seq + " --unknown --roi 10,10,0,5", "no area"},
           Case{"track " + seq + " --unknown --init gt --depth stereo", "two cameras"},
           Case{"track " + seq + " --unknown --init gt --depth lidar", "lidar"},
           Case{"track " + seq + " --unknown --init gt --update sometimes", "sometimes"},
           Case{"track " + seq + " --unknown --init 0,0,1,0,0,0,1", "must be 'gt'"},
           Case{"model " + seq + " --frame 99 --init gt --out x.ply", "--frame 99"},
           Case{"model " + seq + " --roi 0,0,4,4 --out x.ply", "8x8"},
           Case{"model " + seq + " --roi -60,-60,80,80 --out x.ply", "image border"},
           Case{"model " + seq + " --mask /nonexistent.png --out x.ply", "does not exist"},
       }) {
    const testing::CliResult r = RunCli(c.args);
    EXPECT_EQ(r.exit_code, 1) << c.args;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << "\n" << r.err;
  }
}

}  // namespace
}  // namespace unseen
