// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/select/interest_filter_bank.h"

#include <utility>

#include "unseen/util/error.h"
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

std::unique_ptr<InterestFilter> MakeFilter(const YAML::Node& node, const std::string& where) {
  UNSEEN_CHECK(node.IsMap() && node["type"].IsDefined() && node["type"].IsScalar(),
               "{}: each filter is a map with a 'type' (colour, motion, velocity, position)",
               where);
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
  } catch (const Error& e) {
    const std::string message = e.what();
    // Option checks do not know the file: add it.
    if (message.rfind(where, 0) == 0) throw;
    ThrowError("{}: {}", where, message);
  }
  ThrowError("{}.type: '{}' is not a filter (colour, motion, velocity, position)", where, type);
}

InterestFilterBank FromYaml(const YAML::Node& root, const std::string& what) {
  UNSEEN_CHECK(root.IsMap() && root["filters"].IsDefined() && root["filters"].IsSequence(),
               "{}: expected a map with a 'filters' list", what);
  for (const auto& entry : root) {
    const std::string key = YamlKeyName(entry.first, what);
    UNSEEN_CHECK(key == "filters", "{}: unknown key '{}' (only 'filters')", what, key);
  }
  InterestFilterBank bank;
  const YAML::Node& list = root["filters"];
  for (size_t i = 0; i < list.size(); ++i) {
    bank.Add(MakeFilter(list[i], what + ": filters[" + std::to_string(i) + "]"));
  }
  return bank;
}

}  // namespace

InterestFilterBank ParseInterestFilterBank(const std::string& yaml_text, const std::string& what) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    ThrowError("{}: malformed YAML: {}", what, e.what());
  }
  return FromYaml(root, what);
}

InterestFilterBank LoadInterestFilterBank(const std::string& path) {
  return FromYaml(LoadYamlFile(path, "interest filter"), path);
}

}  // namespace unseen
