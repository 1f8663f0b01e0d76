// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/select/interest_filter_bank.h"

#include <filesystem>
#include <utility>

#include "unseen/image/image_io.h"
#include "unseen/select/cooccurrence_filter.h"
#include "unseen/select/recognition_filter.h"
#include "unseen/util/error.h"
#include "unseen/util/files.h"
#include "unseen/util/yaml_options.h"

namespace unseen {

void InterestFilterBank::Add(std::unique_ptr<InterestFilter> filter) {
  UNSEEN_CHECK(filter != nullptr, "InterestFilterBank: no filter to add");
  filters_.push_back(std::move(filter));
}

cv::Mat InterestFilterBank::Apply(const FilterFrame& frame) {
  cv::Mat interest(frame.image.size(), CV_32FC1, cv::Scalar(1.0f));
  for (const std::unique_ptr<InterestFilter>& f : filters_) f->Apply(frame, &interest);
  return interest;
}

bool InterestFilterBank::ready() const {
  for (const std::unique_ptr<InterestFilter>& f : filters_) {
    if (!f->ready()) return false;
  }
  return true;
}

namespace {

// The setter for "type", already read.
YamlSetter Ignore() {
  return [](const YAML::Node&, const std::string&) {};
}

constexpr const char* kTypes =
    "colour, motion, velocity, tracked_motion, position, cooccurrence, recognition";

// `path` as given, or under `base_folder` when it is relative and the folder is known.
std::string ResolvePath(const std::string& path, const std::string& base_folder) {
  if (base_folder.empty() || path.empty() || std::filesystem::path(path).is_absolute()) {
    return path;
  }
  return (std::filesystem::path(base_folder) / path).string();
}

// The image file a key names must exist (a clearer message than the reader's).
void CheckImageFile(const std::string& path, const std::string& key) {
  UNSEEN_CHECK(!path.empty(), "{}: no image path", key);
  UNSEEN_CHECK(IsFile(path), "{}: image file '{}' not found", key, path);
}

cv::Rect RectFromYaml(const std::vector<int>& v, const std::string& key) {
  std::string text;
  for (int x : v) text += (text.empty() ? "" : ", ") + std::to_string(x);
  UNSEEN_CHECK(v.size() == 4, "{}: [{}] must be [x, y, width, height] px", key, text);
  return cv::Rect(v[0], v[1], v[2], v[3]);
}

std::unique_ptr<InterestFilter> MakeCooccurrence(const YAML::Node& node, const std::string& where,
                                                 const std::string& base_folder) {
  CooccurrenceFilterOptions o;
  std::vector<int> rect;
  ApplyYamlSection(node, where,
                   {{"type", Ignore()},
                    {"reference_image", YamlField(&o.reference_image)},
                    {"reference_rect", YamlField(&rect)},
                    {"colours", YamlField(&o.colours)},
                    {"max_colour_distance", YamlField(&o.max_colour_distance)},
                    {"distance_edges_px", YamlField(&o.distance_edges_px)},
                    {"pixel_step", YamlField(&o.pixel_step)},
                    {"stride_px", YamlField(&o.stride_px)},
                    {"scales", YamlField(&o.scales)},
                    {"min_score", YamlField(&o.min_score)},
                    {"full_score", YamlField(&o.full_score)}});
  UNSEEN_CHECK(!o.reference_image.empty(), "{}: a cooccurrence filter needs a reference_image",
               where);
  if (node["reference_rect"].IsDefined()) {
    o.reference_rect = RectFromYaml(rect, where + ".reference_rect");
  }
  o.reference_image = ResolvePath(o.reference_image, base_folder);
  o.Check();  // before reading the image
  CheckImageFile(o.reference_image, where + ".reference_image");
  return std::make_unique<CooccurrenceFilter>(o);
}

std::unique_ptr<InterestFilter> MakeRecognition(const YAML::Node& node, const std::string& where,
                                                const std::string& base_folder) {
  FeatureRecognizerOptions o;
  std::vector<std::string> images;
  std::vector<std::vector<int>> rects;
  ApplyYamlSection(node, where,
                   {{"type", Ignore()},
                    {"reference_images", YamlField(&images)},
                    {"reference_rects", YamlField(&rects)},
                    {"reference_features", YamlField(&o.reference_features)},
                    {"frame_features", YamlField(&o.frame_features)},
                    {"ratio", YamlField(&o.ratio)},
                    {"ransac_threshold_px", YamlField(&o.ransac_threshold_px)},
                    {"min_inliers", YamlField(&o.min_inliers)},
                    {"min_inlier_ratio", YamlField(&o.min_inlier_ratio)},
                    {"full_score_inliers", YamlField(&o.full_score_inliers)},
                    {"min_side_px", YamlField(&o.min_side_px)},
                    {"min_area_px2", YamlField(&o.min_area_px2)},
                    {"max_area_fraction", YamlField(&o.max_area_fraction)},
                    {"max_area_change", YamlField(&o.max_area_change)}});
  UNSEEN_CHECK(!images.empty(), "{}: a recognition filter needs reference_images (a list)", where);
  UNSEEN_CHECK(rects.empty() || rects.size() == images.size(),
               "{}.reference_rects: {} rectangles for {} reference_images; give one per image",
               where, rects.size(), images.size());
  auto recognizer = std::make_unique<FeatureRecognizer>(o);
  for (size_t i = 0; i < images.size(); ++i) {
    const std::string key = fmt::format("{}.reference_images[{}]", where, i);
    const std::string path = ResolvePath(images[i], base_folder);
    const cv::Rect rect =
        rects.empty() ? cv::Rect()
                      : RectFromYaml(rects[i], fmt::format("{}.reference_rects[{}]", where, i));
    CheckImageFile(path, key);
    recognizer->AddReference(LoadColorImage(path), rect, fmt::format("{} ('{}')", key, path));
  }
  return std::make_unique<RecognitionFilter>(std::move(recognizer));
}

std::unique_ptr<InterestFilter> MakeFilter(const YAML::Node& node, const std::string& where,
                                           const std::string& base_folder) {
  UNSEEN_CHECK(node.IsMap() && node["type"].IsDefined() && node["type"].IsScalar(),
               "{}: each filter is a map with a 'type' ({})", where, kTypes);
  const std::string type = node["type"].Scalar();
  try {
    if (type == "colour") {
      std::vector<std::vector<double>> rgb;
      ColourFilterOptions o;
      ApplyYamlSection(
          node, where,
          {{"type", Ignore()}, {"colours_rgb", YamlField(&rgb)}, {"radii", YamlField(&o.radii)}});
      for (size_t i = 0; i < rgb.size(); ++i) {
        UNSEEN_CHECK(rgb[i].size() == 3, "{}.colours_rgb[{}] must be [r, g, b]", where, i);
        o.colours_bgr.emplace_back(rgb[i][2], rgb[i][1], rgb[i][0]);
      }
      return std::make_unique<ColourFilter>(o);
    }
    if (type == "motion") {
      MotionFilterOptions o;
      ApplyYamlSection(node, where,
                       {{"type", Ignore()},
                        {"history", YamlField(&o.history)},
                        {"var_threshold", YamlField(&o.var_threshold)},
                        {"detect_shadows", YamlField(&o.detect_shadows)},
                        {"learning_rate", YamlField(&o.learning_rate)},
                        {"warmup_frames", YamlField(&o.warmup_frames)},
                        {"open_px", YamlField(&o.open_px)}});
      return std::make_unique<MotionFilter>(o);
    }
    if (type == "velocity") {
      std::vector<double> direction{1.0, 0.0};
      VelocityFilterOptions o;
      ApplyYamlSection(node, where,
                       {{"type", Ignore()},
                        {"direction", YamlField(&direction)},
                        {"min_speed_px", YamlField(&o.min_speed_px)},
                        {"max_angle_deg", YamlField(&o.max_angle_deg)}});
      UNSEEN_CHECK(direction.size() == 2, "{}: direction must be [x, y]", where);
      o.direction = Eigen::Vector2d(direction[0], direction[1]);
      return std::make_unique<VelocityFilter>(o);
    }
    if (type == "tracked_motion") {
      TrackedMotionFilterOptions o;
      ApplyYamlSection(node, where,
                       {{"type", Ignore()},
                        {"max_difference_px", YamlField(&o.max_difference_px)},
                        {"relative_difference", YamlField(&o.relative_difference)},
                        {"min_object_speed_px", YamlField(&o.min_object_speed_px)}});
      return std::make_unique<TrackedMotionFilter>(o);
    }
    if (type == "position") {
      std::vector<double> lo, hi;
      ApplyYamlSection(node, where,
                       {{"type", Ignore()}, {"min_m", YamlField(&lo)}, {"max_m", YamlField(&hi)}});
      UNSEEN_CHECK(lo.size() == 3 && hi.size() == 3, "{}: min_m and max_m must be [x, y, z]",
                   where);
      PositionFilterOptions o;
      o.min_m = Eigen::Vector3d(lo[0], lo[1], lo[2]);
      o.max_m = Eigen::Vector3d(hi[0], hi[1], hi[2]);
      return std::make_unique<PositionFilter>(o);
    }
    if (type == "cooccurrence") return MakeCooccurrence(node, where, base_folder);
    if (type == "recognition") return MakeRecognition(node, where, base_folder);
  } catch (const Error& e) {
    const std::string message = e.what();
    // Option checks do not know the file: add it.
    if (message.rfind(where, 0) == 0) throw;
    ThrowError("{}: {}", where, message);
  } catch (const cv::Exception& e) {  // an image OpenCV could not decode, say
    ThrowError("{}: OpenCV: {}", where, e.what());
  }
  ThrowError("{}.type: '{}' is not a filter ({})", where, type, kTypes);
}

InterestFilterBank FromYaml(const YAML::Node& root, const std::string& what,
                            const std::string& base_folder) {
  UNSEEN_CHECK(root.IsMap() && root["filters"].IsDefined() && root["filters"].IsSequence(),
               "{}: expected a map with a 'filters' list", what);
  for (const auto& entry : root) {
    const std::string key = YamlKeyName(entry.first, what);
    UNSEEN_CHECK(key == "filters", "{}: unknown key '{}' (only 'filters')", what, key);
  }
  InterestFilterBank bank;
  const YAML::Node& list = root["filters"];
  for (size_t i = 0; i < list.size(); ++i) {
    bank.Add(MakeFilter(list[i], what + ": filters[" + std::to_string(i) + "]", base_folder));
  }
  return bank;
}

}  // namespace

InterestFilterBank ParseInterestFilterBank(const std::string& yaml_text, const std::string& what,
                                           const std::string& base_folder) {
  const YAML::Node root = ParseYamlText(yaml_text, what);
  return FromYaml(root, what, base_folder);
}

InterestFilterBank LoadInterestFilterBank(const std::string& path) {
  std::string folder = std::filesystem::path(path).parent_path().string();
  if (folder.empty()) folder = ".";
  return FromYaml(LoadYamlFile(path, "interest filter"), path, folder);
}

}  // namespace unseen
