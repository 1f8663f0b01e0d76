// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/io/pose_stream.h"

#include <filesystem>
#include <fstream>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "unseen/util/error.h"
#include "unseen/util/testing.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;

fs::path TestDir() { return testing::TestDir("pose_stream"); }

void WriteText(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

std::vector<PoseRecord> RandomRecords(int n) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<PoseRecord> records;
  for (int i = 0; i < n; ++i) {
    PoseRecord r;
    r.frame = i;
    r.time_s = i / 30.0;
    r.status = i % 5 == 3 ? TrackStatus::kLost
                          : (i % 7 == 4 ? TrackStatus::kSearching : TrackStatus::kTracking);
    r.confidence = (i % 10) / 9.0;
    Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
    r.world_from_obj = Rigid3d(q, Eigen::Vector3d(normal(rng), normal(rng), 1.0 + normal(rng)));
    if (i % 2 == 0) r.process_ms = 3.25 + i;
    records.push_back(r);
  }
  return records;
}

void ExpectSame(const std::vector<PoseRecord>& a, const std::vector<PoseRecord>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].frame, b[i].frame);
    EXPECT_DOUBLE_EQ(a[i].time_s, b[i].time_s);
    EXPECT_EQ(a[i].status, b[i].status);
    EXPECT_DOUBLE_EQ(a[i].confidence, b[i].confidence);
    EXPECT_LT(Difference(a[i].world_from_obj, b[i].world_from_obj).translation, 1e-12);
    EXPECT_LT(Difference(a[i].world_from_obj, b[i].world_from_obj).rotation_rad, 1e-9);
    EXPECT_EQ(a[i].process_ms.has_value(), b[i].process_ms.has_value());
    if (a[i].process_ms && b[i].process_ms) {
      EXPECT_DOUBLE_EQ(*a[i].process_ms, *b[i].process_ms);
    }
  }
}

// Checks that `fn` throws unseen::Error whose message contains every substring.
using testing::ExpectError;

const char kHeader[] = "frame,time_s,status,confidence,tx,ty,tz,qx,qy,qz,qw\n";

TEST(PoseStream, StatusStrings) {
  for (TrackStatus s : {TrackStatus::kTracking, TrackStatus::kLost, TrackStatus::kSearching}) {
    EXPECT_EQ(ParseTrackStatus(ToString(s)), s);
  }
  ExpectError([] { ParseTrackStatus("found", "field x"); }, {"field x", "found"});
}

TEST(PoseStream, CsvRoundTrip) {
  const fs::path path = TestDir() / "poses.csv";
  const std::vector<PoseRecord> records = RandomRecords(40);
  WritePoseStream(path.string(), records);
  ExpectSame(records, ReadPoseStream(path.string()));
}

TEST(PoseStream, JsonLinesRoundTrip) {
  const fs::path dir = TestDir();
  const std::vector<PoseRecord> records = RandomRecords(40);
  for (const char* name : {"poses.jsonl", "poses.json"}) {
    WritePoseStream((dir / name).string(), records);
    ExpectSame(records, ReadPoseStream((dir / name).string()));
  }
}

TEST(PoseStream, WriterFlushesEveryRecord) {
  const fs::path path = TestDir() / "poses.csv";
  PoseStreamWriter writer(path.string());
  const std::vector<PoseRecord> records = RandomRecords(3);
  writer.Write(records[0]);
  writer.Write(records[1]);
  // Read while the writer is still open, as after a killed run.
  EXPECT_EQ(ReadPoseStream(path.string()).size(), 2u);
}

TEST(PoseStream, ReadsWithoutProcessMsAndWithExtraColumns) {
  const fs::path dir = TestDir();
  WriteText(dir / "a.csv",
            "frame, time_s,status,confidence,tx,ty,tz,qx,qy,qz,qw\n"
            "0,0,tracking,0.9,0.1,0.2,1.5,0,0,0,1\n\n"
            "1,0.0333,lost,0,0.1,0.2,1.5,0,0,0.70710678,0.70710678\n");
  const std::vector<PoseRecord> a = ReadPoseStream((dir / "a.csv").string());
  ASSERT_EQ(a.size(), 2u);
  EXPECT_FALSE(a[0].process_ms.has_value());
  EXPECT_EQ(a[1].status, TrackStatus::kLost);
  EXPECT_NEAR(a[0].world_from_obj.translation().z(), 1.5, 1e-15);

  // Columns in another order plus unknown ones.
  WriteText(dir / "b.csv",
            "qw,qx,qy,qz,tx,ty,tz,frame,time_s,status,confidence,note,process_ms\n"
            "1,0,0,0,1,2,3,5,0.5,searching,0.5,hello,12.5\n");
  const std::vector<PoseRecord> b = ReadPoseStream((dir / "b.csv").string());
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(b[0].frame, 5);
  EXPECT_EQ(b[0].status, TrackStatus::kSearching);
  EXPECT_EQ(b[0].world_from_obj.translation(), Eigen::Vector3d(1, 2, 3));
  EXPECT_DOUBLE_EQ(*b[0].process_ms, 12.5);

  WriteText(
      dir / "c.jsonl",
      R"({"frame":2,"time_s":0.1,"status":"tracking","confidence":1,"tx":0,"ty":0,"tz":1,"qx":0,"qy":0,"qz":0,"qw":1,"extra":[1,2]})"
      "\n");
  const std::vector<PoseRecord> c = ReadPoseStream((dir / "c.jsonl").string());
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].frame, 2);
  EXPECT_FALSE(c[0].process_ms.has_value());
}

TEST(PoseStream, RejectsNaN) {
  const fs::path path = TestDir() / "nan.csv";
  WriteText(path, std::string(kHeader) + "0,0,tracking,1,0,0,1,0,0,0,1\n" +
                      "1,0.03,tracking,1,nan,0,1,0,0,0,1\n");
  ExpectError([&] { ReadPoseStream(path.string()); }, {"nan.csv:3", "\"tx\"", "nan"});
}

TEST(PoseStream, RejectsNullInJsonLines) {
  const fs::path path = TestDir() / "null.jsonl";
  WriteText(
      path,
      R"({"frame":0,"time_s":0,"status":"tracking","confidence":1,"tx":0,"ty":null,"tz":1,"qx":0,"qy":0,"qz":0,"qw":1})"
      "\n");
  ExpectError([&] { ReadPoseStream(path.string()); }, {"null.jsonl:1", "\"ty\"", "null"});
}

TEST(PoseStream, RejectsNonUnitQuaternion) {
  const fs::path path = TestDir() / "q.csv";
  WriteText(path, std::string(kHeader) + "0,0,tracking,1,0,0,1,0,0,0,1.01\n");
  ExpectError([&] { ReadPoseStream(path.string()); }, {"q.csv:2", "quaternion", "1.01"});
}

TEST(PoseStream, PoseTextParsedOrRejectedByName) {
  // A file's line, blanks and trailing newline included; the quaternion is normalised.
  const Rigid3d pose = ParsePoseText(" 0.1, -0.2,0.5, 0,0,0.6,0.8\n", "init_pose.txt");
  EXPECT_TRUE(pose.translation().isApprox(Eigen::Vector3d(0.1, -0.2, 0.5)));
  EXPECT_NEAR(pose.rotation().z(), 0.6, 1e-12);
  EXPECT_NEAR(pose.rotation().w(), 0.8, 1e-12);
  EXPECT_TRUE(
      ParsePoseText("0,0,0,0,0,0,2", "p").rotation().isApprox(Eigen::Quaterniond::Identity()));
  auto rejects = [](const std::string& text, const std::string& says) {
    ExpectError([&] { ParsePoseText(text, "init_pose.txt"); }, {"init_pose.txt", says});
  };
  rejects("0,0,0,0,0,0", "seven numbers");
  rejects("0,0,0,0,0,0,1,0", "seven numbers");
  rejects("0,0,x,0,0,0,1", "value 3 'x'");
  rejects("0,0,1m,0,0,0,1", "value 3 '1m'");
  rejects("0,,0,0,0,0,1", "value 2 ''");
  rejects("0,0,0,0,0,nan,1", "value 6 'nan'");
  rejects("0,0,0,0,0,0,0", "quaternion");
  rejects("", "seven numbers");
}

TEST(PoseStream, RejectsUnknownStatus) {
  const fs::path path = TestDir() / "s.csv";
  WriteText(path, std::string(kHeader) + "0,0,Tracked,1,0,0,1,0,0,0,1\n");
  ExpectError([&] { ReadPoseStream(path.string()); }, {"s.csv:2", "\"status\"", "Tracked"});
}

TEST(PoseStream, RejectsMissingColumn) {
  const fs::path path = TestDir() / "m.csv";
  WriteText(path, "frame,time_s,status,confidence,tx,ty,qx,qy,qz,qw\n0,0,tracking,1,0,0,0,0,0,1\n");
  ExpectError([&] { ReadPoseStream(path.string()); }, {"m.csv:1", "\"tz\""});
  const fs::path jsonl = path.parent_path() / "m.jsonl";
  WriteText(
      jsonl,
      R"({"frame":0,"time_s":0,"status":"tracking","tx":0,"ty":0,"tz":1,"qx":0,"qy":0,"qz":0,"qw":1})"
      "\n");
  ExpectError([&] { ReadPoseStream(jsonl.string()); }, {"m.jsonl:1", "\"confidence\"", "missing"});
}

TEST(PoseStream, RejectsEmptyFile) {
  const fs::path dir = TestDir();
  WriteText(dir / "empty.csv", "");
  ExpectError([&] { ReadPoseStream((dir / "empty.csv").string()); }, {"empty.csv", "empty"});
  WriteText(dir / "blank.jsonl", "\n  \n");
  ExpectError([&] { ReadPoseStream((dir / "blank.jsonl").string()); }, {"blank.jsonl", "empty"});
  ExpectError([&] { ReadPoseStream((dir / "absent.csv").string()); }, {"absent.csv", "not found"});
}

TEST(PoseStream, RejectsMalformedLines) {
  const fs::path dir = TestDir();
  WriteText(dir / "short.csv", std::string(kHeader) + "0,0,tracking,1,0,0\n");
  ExpectError([&] { ReadPoseStream((dir / "short.csv").string()); }, {"short.csv:2", "fields"});
  WriteText(dir / "word.csv", std::string(kHeader) + "0,0,tracking,1,abc,0,1,0,0,0,1\n");
  ExpectError([&] { ReadPoseStream((dir / "word.csv").string()); },
              {"word.csv:2", "\"tx\"", "abc"});
  WriteText(dir / "bad.jsonl", "{\"frame\": 0,\n");
  ExpectError([&] { ReadPoseStream((dir / "bad.jsonl").string()); },
              {"bad.jsonl:1", "malformed JSON"});
  WriteText(dir / "conf.csv", std::string(kHeader) + "0,0,tracking,1.5,0,0,1,0,0,0,1\n");
  ExpectError([&] { ReadPoseStream((dir / "conf.csv").string()); },
              {"conf.csv:2", "confidence", "1.5"});
  WriteText(dir / "dup.csv", std::string(kHeader) + "0,0,tracking,1,0,0,1,0,0,0,1\n" +
                                 "0,0,tracking,1,0,0,1,0,0,0,1\n");
  ExpectError([&] { ReadPoseStream((dir / "dup.csv").string()); },
              {"dup.csv", "frame 0", "more than once"});
  WriteText(dir / "frac.csv", std::string(kHeader) + "1.5,0,tracking,1,0,0,1,0,0,0,1\n");
  ExpectError([&] { ReadPoseStream((dir / "frac.csv").string()); },
              {"frac.csv:2", "\"frame\"", "1.5"});
}

TEST(PoseStream, WriterRejectsBadInput) {
  const fs::path dir = TestDir();
  ExpectError([&] { PoseStreamWriter((dir / "poses.txt").string()); }, {"poses.txt", ".txt"});
  ExpectError([&] { PoseStreamWriter((dir / "no_such_dir" / "p.csv").string()); }, {"p.csv"});
  PoseStreamWriter writer((dir / "p.csv").string());
  PoseRecord r;
  r.world_from_obj.set_translation(Eigen::Vector3d(0, std::nan(""), 1));
  ExpectError([&] { writer.Write(r); }, {"p.csv", "frame 0"});
}

TEST(PoseStream, BopSceneGtRoundTrip) {
  const fs::path path = TestDir() / "scene_gt.json";
  const std::vector<PoseRecord> records = RandomRecords(30);
  const Rigid3d world_from_cam(Eigen::Quaterniond(0.9, 0.1, -0.2, 0.3),
                               Eigen::Vector3d(0.1, -0.2, 0.05));
  ExportBopSceneGt(path.string(), records, world_from_cam.Inverse(), 7);

  // The file is plain BOP: model->camera in millimetres.
  std::ifstream in(path);
  const nlohmann::json gt = nlohmann::json::parse(in);
  ASSERT_TRUE(gt.contains("0"));
  const auto& t = gt["0"][0]["cam_t_m2c"];
  const Eigen::Vector3d expected_mm =
      (world_from_cam.Inverse() * records[0].world_from_obj).translation() * 1e3;
  EXPECT_NEAR(t[2].get<double>(), expected_mm.z(), 1e-9);
  EXPECT_EQ(gt["0"][0]["obj_id"].get<int>(), 7);

  const std::vector<PoseRecord> back =
      ReadBopSceneGtAsPoses(path.string(), world_from_cam, 7, 30.0);
  std::vector<PoseRecord> tracked;
  for (const PoseRecord& r : records) {
    if (r.status == TrackStatus::kTracking) tracked.push_back(r);
  }
  ASSERT_EQ(back.size(), tracked.size());
  EXPECT_FALSE(gt.contains("3"));  // lost frames are omitted
  for (size_t i = 0; i < back.size(); ++i) {
    EXPECT_EQ(back[i].frame, tracked[i].frame);
    EXPECT_NEAR(back[i].time_s, tracked[i].frame / 30.0, 1e-12);
    EXPECT_LT(Difference(back[i].world_from_obj, tracked[i].world_from_obj).translation, 1e-9);
    EXPECT_LT(Difference(back[i].world_from_obj, tracked[i].world_from_obj).rotation_rad, 1e-9);
  }
  // obj_id 0 picks the first object; an absent object gives no records.
  EXPECT_EQ(ReadBopSceneGtAsPoses(path.string(), world_from_cam, 0, 30.0).size(), back.size());
  EXPECT_TRUE(ReadBopSceneGtAsPoses(path.string(), world_from_cam, 8, 30.0).empty());
}

TEST(PoseStream, BopSceneGtBadInput) {
  const fs::path dir = TestDir();
  WriteText(
      dir / "nan.json",
      R"({"0": [{"obj_id": 1, "cam_R_m2c": [1,0,0,0,1,0,0,0,1], "cam_t_m2c": [0, NaN, 1000]}]})");
  ExpectError([&] { ReadBopSceneGtAsPoses((dir / "nan.json").string(), Rigid3d(), 1, 30); },
              {"nan.json", "malformed JSON"});
  WriteText(
      dir / "rot.json",
      R"({"5": [{"obj_id": 1, "cam_R_m2c": [1,0,0,0,1,0,0,0,2], "cam_t_m2c": [0, 0, 1000]}]})");
  ExpectError([&] { ReadBopSceneGtAsPoses((dir / "rot.json").string(), Rigid3d(), 1, 30); },
              {"rot.json frame 5", "cam_R_m2c", "orthonormal"});
  WriteText(dir / "short.json",
            R"({"5": [{"obj_id": 1, "cam_R_m2c": [1,0,0,0,1,0,0,0,1], "cam_t_m2c": [0, 0]}]})");
  ExpectError([&] { ReadBopSceneGtAsPoses((dir / "short.json").string(), Rigid3d(), 1, 30); },
              {"short.json frame 5", "cam_t_m2c", "2 values"});
  WriteText(dir / "key.json", R"({"x": []})");
  ExpectError([&] { ReadBopSceneGtAsPoses((dir / "key.json").string(), Rigid3d(), 1, 30); },
              {"key.json", "\"x\""});
}

}  // namespace
}  // namespace unseen
