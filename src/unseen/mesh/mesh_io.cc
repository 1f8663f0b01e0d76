// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/mesh/mesh_io.h"

#include <assimp/config.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/texture.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "unseen/image/image_io.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string LowerExtension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// `<dir>/<stem>_projectors.json` for a mesh file `<dir>/<stem>.<ext>`.
fs::path ProjectorsPath(const fs::path& mesh_path) {
  return mesh_path.parent_path() / (mesh_path.stem().string() + "_projectors.json");
}

// ---------------------------------------------------------------------------------------
// Loading

// `s` without leading and trailing blanks.
std::string Trim(const std::string& s) {
  const size_t first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t\r\n") + 1 - first);
}

// Decodes "%20"-style escapes (glTF URIs are percent-encoded).
std::string PercentDecode(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(static_cast<unsigned char>(s[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(s[i + 2]))) {
      out.push_back(static_cast<char>(std::stoi(s.substr(i + 1, 2), nullptr, 16)));
      i += 2;
    } else {
      out.push_back(s[i]);
    }
  }
  return out;
}

// An embedded texture: compressed (PNG/JPEG bytes, mHeight == 0) or raw BGRA texels.
cv::Mat DecodeEmbeddedTexture(const aiTexture& texture, const std::string& mesh_path,
                              const std::string& name) {
  if (texture.mHeight == 0) {
    const cv::Mat bytes(1, static_cast<int>(texture.mWidth), CV_8UC1,
                        const_cast<aiTexel*>(texture.pcData));
    const cv::Mat image = cv::imdecode(bytes, cv::IMREAD_ANYCOLOR | cv::IMREAD_ANYDEPTH);
    UNSEEN_CHECK(!image.empty(),
                 "{}: embedded texture '{}' ({} bytes, format hint '{}') cannot "
                 "be decoded",
                 mesh_path, name, texture.mWidth, texture.achFormatHint);
    return ToFloatBgr(image, mesh_path + " embedded texture " + name);
  }
  // aiTexel is laid out b, g, r, a: exactly OpenCV's BGRA.
  const cv::Mat bgra(static_cast<int>(texture.mHeight), static_cast<int>(texture.mWidth), CV_8UC4,
                     const_cast<aiTexel*>(texture.pcData));
  return ToFloatBgr(bgra, mesh_path + " embedded texture " + name);
}

// Finds the file a material refers to: relative to the mesh's folder (or absolute), with
// backslashes as separators and percent escapes tolerated. Empty path when not found.
fs::path ResolveTextureFile(const fs::path& mesh_dir, const std::string& reference) {
  std::string ref = reference;
  std::replace(ref.begin(), ref.end(), '\\', '/');
  std::vector<fs::path> candidates;
  for (const std::string& r : {ref, PercentDecode(ref)}) {
    const fs::path p(r);
    candidates.push_back(p.is_absolute() ? p : mesh_dir / p);
  }
  for (const fs::path& c : candidates) {
    std::error_code ec;
    if (fs::is_regular_file(c, ec)) return c;
  }
  return {};
}

// Loads textures once per file even when several materials share them.
class TextureLoader {
 public:
  TextureLoader(const aiScene* scene, const std::string& mesh_path)
      : scene_(scene), mesh_path_(mesh_path), mesh_dir_(fs::path(mesh_path).parent_path()) {}

  // The texture named `reference` by a material (an embedded "*N" / file name, or a file
  // beside the mesh). Throws naming the mesh and the texture when it cannot be read.
  cv::Mat Load(const std::string& untrimmed_reference) {
    const std::string reference = Trim(untrimmed_reference);
    if (scene_ != nullptr) {
      if (const aiTexture* embedded = scene_->GetEmbeddedTexture(reference.c_str())) {
        return DecodeEmbeddedTexture(*embedded, mesh_path_, reference);
      }
    }
    const fs::path file = ResolveTextureFile(mesh_dir_, reference);
    UNSEEN_CHECK(!file.empty(), "{}: texture file '{}' not found (looked in '{}')", mesh_path_,
                 reference, mesh_dir_.string());
    auto it = cache_.find(file.string());
    if (it == cache_.end()) {
      cv::Mat image;
      try {
        image = LoadColorImage(file.string());
      } catch (const Error& e) {
        ThrowError("{}: texture '{}' cannot be read: {}", mesh_path_, reference, e.what());
      }
      it = cache_.emplace(file.string(), image).first;
    }
    return it->second;
  }

 private:
  const aiScene* scene_;
  std::string mesh_path_;
  fs::path mesh_dir_;
  std::map<std::string, cv::Mat> cache_;
};

// Converts assimp material `index` to a Material with its diffuse colour and texture.
Material ConvertMaterial(const aiScene& scene, unsigned index, TextureLoader* textures) {
  const aiMaterial& in = *scene.mMaterials[index];
  Material out;
  aiString name;
  if (in.Get(AI_MATKEY_NAME, name) == AI_SUCCESS) out.name = name.C_Str();
  if (out.name.empty()) out.name = "material_" + std::to_string(index);
  aiColor4D colour;
  if (in.Get(AI_MATKEY_COLOR_DIFFUSE, colour) == AI_SUCCESS ||
      in.Get(AI_MATKEY_BASE_COLOR, colour) == AI_SUCCESS) {
    out.diffuse_bgr = Eigen::Vector3f(colour.b, colour.g, colour.r).cwiseMax(0.0f).cwiseMin(1.0f);
  }
  for (aiTextureType type : {aiTextureType_DIFFUSE, aiTextureType_BASE_COLOR}) {
    if (in.GetTextureCount(type) == 0) continue;
    aiString reference;
    if (in.GetTexture(type, 0, &reference) != AI_SUCCESS || reference.length == 0) continue;
    out.texture = textures->Load(reference.C_Str());
    out.texture_path = Trim(reference.C_Str());
    if (!out.texture_path.empty() && out.texture_path[0] == '*') {
      out.texture_path.clear();  // embedded: no file of its own
    }
    break;
  }
  return out;
}

// The `comment TextureFile <name>` line of a PLY header (as BOP models carry), or "".
std::string ReadPlyTextureComment(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  for (int n = 0; n < 10000 && std::getline(in, line); ++n) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line == "end_header") break;
    std::istringstream words(line);
    std::string comment, key;
    words >> comment >> key;
    if (comment == "comment" && key == "TextureFile") {
      std::string rest;
      std::getline(words, rest);
      return Trim(rest);
    }
  }
  return "";
}

// Value of field `key` of `object`, or an error naming the file and field.
template <typename T>
T GetField(const json& object, const std::string& key, const std::string& file,
           const std::string& where) {
  UNSEEN_CHECK(object.is_object() && object.contains(key), "{}: {} has no field '{}'", file, where,
               key);
  try {
    return object.at(key).get<T>();
  } catch (const json::exception& e) {
    ThrowError("{}: {}.{} has the wrong type ({}): {}", file, where, key, object.at(key).dump(),
               e.what());
  }
}

// Reads the projective textures written by SaveMesh; translations are in file units.
std::vector<Projector> ReadProjectors(const fs::path& json_path) {
  const std::string file = json_path.string();
  std::ifstream in(json_path);
  UNSEEN_CHECK(in.good(), "{}: cannot open projector file", file);
  // Nesting is limited: the value is copied and printed recursively below.
  constexpr int kMaxDepth = 64;
  const json::parser_callback_t limit_depth = [&](int depth, json::parse_event_t, json&) {
    UNSEEN_CHECK(depth <= kMaxDepth, "{}: JSON nested deeper than {} levels", file, kMaxDepth);
    return true;
  };
  json root;
  try {
    root = json::parse(in, limit_depth);
  } catch (const json::exception& e) {
    ThrowError("{}: malformed JSON: {}", file, e.what());
  }
  UNSEEN_CHECK(root.is_object() && root.contains("projectors") && root["projectors"].is_array(),
               "{}: expected an object with a 'projectors' array", file);
  std::vector<Projector> projectors;
  const json& list = root["projectors"];
  for (size_t i = 0; i < list.size(); ++i) {
    const json& p = list[i];
    const std::string where = "projectors[" + std::to_string(i) + "]";
    Projector projector;
    const json camera = GetField<json>(p, "camera", file, where);
    const std::string cwhere = where + ".camera";
    PinholeCamera& cam = projector.camera;
    cam.width = GetField<int>(camera, "width", file, cwhere);
    cam.height = GetField<int>(camera, "height", file, cwhere);
    cam.fx = GetField<double>(camera, "fx", file, cwhere);
    cam.fy = GetField<double>(camera, "fy", file, cwhere);
    cam.cx = GetField<double>(camera, "cx", file, cwhere);
    cam.cy = GetField<double>(camera, "cy", file, cwhere);
    if (camera.contains("distortion")) {
      cam.distortion = GetField<std::vector<double>>(camera, "distortion", file, cwhere);
    }
    cam.Check(file + " " + cwhere);

    const json pose = GetField<json>(p, "cam_from_obj", file, where);
    const std::string pwhere = where + ".cam_from_obj";
    const auto rows = GetField<std::vector<std::vector<double>>>(pose, "rotation", file, pwhere);
    const auto t = GetField<std::vector<double>>(pose, "translation", file, pwhere);
    UNSEEN_CHECK(
        rows.size() == 3 && rows[0].size() == 3 && rows[1].size() == 3 && rows[2].size() == 3,
        "{}: {}.rotation must be 3x3, got {}", file, pwhere, pose["rotation"].dump());
    UNSEEN_CHECK(t.size() == 3, "{}: {}.translation must have 3 entries, got {}", file, pwhere,
                 pose["translation"].dump());
    Eigen::Matrix3d rotation;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) rotation(r, c) = rows[r][c];
    }
    const Eigen::Vector3d translation(t[0], t[1], t[2]);
    UNSEEN_CHECK(translation.allFinite(), "{}: {}.translation is not finite: {}", file, pwhere,
                 pose["translation"].dump());
    projector.cam_from_obj =
        Rigid3d::FromRotationMatrix(rotation, translation, file + " " + pwhere + ".rotation");

    const std::string image_name = GetField<std::string>(p, "image", file, where);
    const fs::path image_path = json_path.parent_path() / image_name;
    UNSEEN_CHECK(fs::is_regular_file(image_path), "{}: {}.image '{}' not found", file, where,
                 image_path.string());
    projector.image = LoadColorImage(image_path.string());
    UNSEEN_CHECK(projector.image.cols == cam.width && projector.image.rows == cam.height,
                 "{}: {}.image '{}' is {}x{} but the camera is {}x{}", file, where, image_name,
                 projector.image.cols, projector.image.rows, cam.width, cam.height);
    projectors.push_back(std::move(projector));
  }
  return projectors;
}

// The whole file as text.
std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  UNSEEN_CHECK(in.good(), "{}: cannot open mesh file", path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Checks made before assimp 5.2 reads a file, for input it does not survive.
//
// PLY: assimp mishandles malformed headers. Without an end_header line it loops for ever; a
// face element without vertex indices (but e.g. texcoords) makes it dereference a null
// pointer; lines it does not know and repeated elements have it free memory it did not
// allocate; an element count larger than the file has it reserve gigabytes. The header is
// checked line by line against the PLY grammar first.
void CheckPlyHeader(const std::string& path) {
  static const std::set<std::string> kIntegerTypes = {"char",  "uchar",  "short", "ushort",
                                                      "int",   "uint",   "int8",  "uint8",
                                                      "int16", "uint16", "int32", "uint32"};
  static const std::set<std::string> kTypes = [] {
    std::set<std::string> types = kIntegerTypes;
    types.insert({"float", "double", "float32", "float64"});
    return types;
  }();
  // Element and property names are words that do not start with a digit: assimp takes
  // "element 4294967295vertex 4" for 4294967295 vertices.
  const auto is_name = [](const std::string& word) {
    return !word.empty() && !std::isdigit(static_cast<unsigned char>(word[0])) &&
           std::all_of(word.begin(), word.end(), [](unsigned char c) {
             return std::isalnum(c) || c == '_' || c == '-' || c == '.';
           });
  };
  std::error_code ec;
  const uintmax_t file_size = fs::file_size(path, ec);
  std::ifstream in(path, std::ios::binary);
  std::string line;
  bool format = false, face_indices = false;
  std::set<std::string> elements, properties;
  std::string element;
  for (int n = 1; n <= 100000 && std::getline(in, line); ++n) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream stream(line);
    const std::vector<std::string> words{std::istream_iterator<std::string>(stream),
                                         std::istream_iterator<std::string>()};
    const std::string keyword = words.empty() ? "" : words[0];
    bool valid = false;
    if (n == 1) {
      valid = words.size() == 1 && keyword == "ply";
    } else if (keyword == "comment" || keyword == "obj_info") {
      valid = true;
    } else if (keyword == "format") {
      valid = !format && words.size() == 3 &&
              (words[1] == "ascii" || words[1] == "binary_little_endian" ||
               words[1] == "binary_big_endian");
      format = true;
    } else if (keyword == "element") {
      const bool count_ok = words.size() == 3 && !words[2].empty() && words[2].size() <= 12 &&
                            words[2].find_first_not_of("0123456789") == std::string::npos;
      valid = count_ok && is_name(words[1]) && elements.insert(words[1]).second;
      if (valid) {
        UNSEEN_CHECK(std::stoull(words[2]) <= file_size,
                     "{}: PLY element '{}' has {} entries, more than the file's {} bytes can hold",
                     path, words[1], words[2], file_size);
        element = words[1];
        properties.clear();
      }
    } else if (keyword == "property" && !element.empty()) {
      const bool list = words.size() == 5 && words[1] == "list";
      valid = list ? kIntegerTypes.count(words[2]) && kTypes.count(words[3])
                   : words.size() == 3 && kTypes.count(words[1]);
      valid = valid && is_name(words.back()) && properties.insert(words.back()).second;
      face_indices = face_indices || (element == "face" && list &&
                                      (words[4] == "vertex_indices" || words[4] == "vertex_index"));
    } else if (keyword == "end_header") {
      UNSEEN_CHECK(words.size() == 1 && format, "{}: PLY header line {} is not valid: '{}'", path,
                   n, line.substr(0, 80));
      UNSEEN_CHECK(!elements.count("face") || face_indices,
                   "{}: PLY element 'face' has no vertex_indices list property", path);
      return;
    }
    UNSEEN_CHECK(valid, "{}: PLY header line {} is not valid: '{}'", path, n, line.substr(0, 80));
  }
  ThrowError("{}: PLY header has no end_header line", path);
}

// OBJ: assimp crashes on face corners that refer to normals (or uvs) the file does not
// have. Every index of the f, l and p lines is checked: positive ones against the file's
// counts of v, vt and vn, negative (relative) ones against those read so far.
void CheckObjIndices(const std::string& path) {
  const std::string text = ReadText(path);
  const auto for_each_line = [&](const auto& visit) {
    std::istringstream in(text);
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
      line = line.substr(0, line.find('#'));
      std::istringstream words(line);
      std::string keyword;
      words >> keyword;
      visit(n, keyword, words, line);
    }
  };
  const char* kNames[3] = {"vertex", "texture coordinate", "normal"};
  int64_t total[3] = {0, 0, 0}, so_far[3] = {0, 0, 0};
  const auto count = [](const std::string& keyword, int64_t* counts) {
    if (keyword == "v") ++counts[0];
    if (keyword == "vt") ++counts[1];
    if (keyword == "vn") ++counts[2];
  };
  for_each_line([&](int, const std::string& keyword, std::istream&, const std::string&) {
    count(keyword, total);
  });
  for_each_line([&](int n, const std::string& keyword, std::istream& words,
                    const std::string& line) {
    count(keyword, so_far);
    if (keyword != "f" && keyword != "l" && keyword != "p") return;
    std::string corner;
    while (words >> corner) {
      size_t start = 0;
      for (int k = 0; k < 3 && start <= corner.size(); ++k) {
        const size_t slash = std::min(corner.find('/', start), corner.size());
        const std::string index = corner.substr(start, slash - start);
        start = slash + 1;
        if (index.empty() && k > 0) continue;  // "1//3": no texture coordinate
        char* end = nullptr;
        const long long i = std::strtoll(index.c_str(), &end, 10);
        const bool valid =
            !index.empty() && *end == '\0' && i != 0 && (i > 0 ? i <= total[k] : -i <= so_far[k]);
        UNSEEN_CHECK(valid, "{}: line {}: '{}' refers to {} {}, but the file has {}", path, n,
                     line.substr(0, 80), kNames[k], index, total[k]);
      }
      UNSEEN_CHECK(start > corner.size(), "{}: line {}: '{}' is not v/vt/vn", path, n, corner);
    }
  });
}

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

// Position just after `count =` in `text` at `at` (where "count" starts), or npos when no
// count attribute starts there.
size_t AfterCountAttribute(std::string_view text, size_t at) {
  if (at == 0 || !IsBlank(text[at - 1])) return std::string::npos;  // <vcount>, "account", ...
  size_t i = at + 5;
  while (i < text.size() && IsBlank(text[i])) ++i;
  if (i >= text.size() || text[i] != '=') return std::string::npos;
  return i + 1;
}

// Collada: a <p> index list holding anything but integers and blanks makes assimp loop for
// ever, a data array without a count attribute makes it dereference a null pointer, and a
// count="N" attribute has it reserve memory for N values before it looks at them. Counts
// are checked against the file's size (every value takes at least a byte), so that a short
// file cannot ask for gigabytes.
void CheckColladaText(const std::string& path) {
  const std::string text = ReadText(path);
  for (const char* array : {"<float_array", "<int_array", "<bool_array", "<Name_array",
                            "<IDREF_array", "<SIDREF_array", "<token_array"}) {
    for (size_t at = text.find(array); at != std::string::npos; at = text.find(array, at + 1)) {
      const std::string_view tag =
          std::string_view(text).substr(at, text.find('>', at) - at);  // to the end if no '>'
      bool counted = false;
      for (size_t c = tag.find("count"); c != std::string::npos && !counted;
           c = tag.find("count", c + 1)) {
        counted = AfterCountAttribute(tag, c) != std::string::npos;
      }
      UNSEEN_CHECK(counted, "{}: {}> element without a count attribute", path, array);
    }
  }
  for (size_t at = text.find("count"); at != std::string::npos; at = text.find("count", at + 1)) {
    size_t i = AfterCountAttribute(text, at);
    if (i == std::string::npos) continue;
    while (i < text.size() && IsBlank(text[i])) ++i;
    if (i >= text.size() || (text[i] != '"' && text[i] != '\'')) continue;
    const size_t close = text.find(text[i], i + 1);
    if (close == std::string::npos) continue;
    const std::string value = Trim(text.substr(i + 1, close - i - 1));
    // Decimal or 0x-hexadecimal, as assimp's XML reader takes them; a sign wraps around.
    const bool hex = value.rfind("0x", 0) == 0 || value.rfind("0X", 0) == 0;
    const std::string digits = hex ? value.substr(2) : value;
    const bool plain = !digits.empty() && digits.size() <= 12 &&
                       std::all_of(digits.begin(), digits.end(), [&](unsigned char c) {
                         return hex ? std::isxdigit(c) != 0 : std::isdigit(c) != 0;
                       });
    UNSEEN_CHECK(plain && std::stoull(digits, nullptr, hex ? 16 : 10) <= text.size(),
                 "{}: count=\"{}\" is not a number of values the file can hold ({} bytes)", path,
                 value, text.size());
  }
  for (size_t at = text.find("<p"); at != std::string::npos; at = text.find("<p", at + 1)) {
    const size_t name_end = at + 2;
    if (name_end >= text.size() || (text[name_end] != '>' && !IsBlank(text[name_end]))) continue;
    const size_t open_end = text.find('>', name_end);
    if (open_end == std::string::npos || text[open_end - 1] == '/') continue;
    const size_t end = std::min(text.find('<', open_end), text.size());
    const std::string list = text.substr(open_end + 1, end - open_end - 1);
    const size_t bad = list.find_first_not_of("0123456789+- \t\r\n");
    UNSEEN_CHECK(bad == std::string::npos,
                 "{}: <p> index list holds '{}', expected integers separated by blanks", path,
                 list.substr(bad, 20));
  }
}

// glTF: assimp parses the JSON recursively, so that deeply nested input exhausts the
// stack, and allocates what a .glb file's header says before it reads it. The nesting of a
// .gltf file, or of a .glb file's JSON chunk, and the lengths in a .glb header are checked
// first.
void CheckGltfText(const std::string& path, bool binary) {
  constexpr int kMaxDepth = 64;
  const std::string text = ReadText(path);
  std::string_view json = text;
  if (binary) {  // "glTF", version, total length, then the JSON chunk's length, type, content
    if (text.size() < 20 || text.compare(0, 4, "glTF") != 0) return;
    uint32_t total = 0, json_length = 0;
    std::memcpy(&total, text.data() + 8, sizeof(total));
    std::memcpy(&json_length, text.data() + 12, sizeof(json_length));
    UNSEEN_CHECK(total >= 20 && total <= text.size() && json_length <= total - 20,
                 "{}: GLB header gives a length of {} bytes and a JSON chunk of {} bytes; the "
                 "file has {} bytes",
                 path, total, json_length, text.size());
    json = json.substr(20, json_length);
  }
  int depth = 0;
  bool in_string = false;
  for (size_t i = 0; i < json.size(); ++i) {
    const char c = json[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      UNSEEN_CHECK(++depth <= kMaxDepth, "{}: glTF JSON nested deeper than {} levels", path,
                   kMaxDepth);
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
}

// Throws naming the file for faces without indices, indices out of range and non-finite
// vertex positions in assimp's raw (not yet post-processed) scene.
void CheckRawScene(const aiScene& scene, const std::string& path) {
  bool any_polygon = false;
  for (unsigned mi = 0; mi < scene.mNumMeshes; ++mi) {
    const aiMesh& mesh = *scene.mMeshes[mi];
    UNSEEN_CHECK(mesh.mVertices != nullptr || mesh.mNumVertices == 0,
                 "{}: sub-mesh {} has no vertex positions", path, mi);
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      UNSEEN_CHECK(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z),
                   "{}: vertex {} of sub-mesh {} is not finite ({} {} {})", path, v, mi, p.x, p.y,
                   p.z);
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      UNSEEN_CHECK(face.mNumIndices > 0 && face.mIndices != nullptr,
                   "{}: face {} of sub-mesh {} has no vertex indices", path, f, mi);
      any_polygon = any_polygon || face.mNumIndices >= 3;
      for (unsigned k = 0; k < face.mNumIndices; ++k) {
        UNSEEN_CHECK(face.mIndices[k] < mesh.mNumVertices,
                     "{}: face {} of sub-mesh {} has vertex index {} out of range [0, {})", path, f,
                     mi, face.mIndices[k], mesh.mNumVertices);
      }
    }
  }
  UNSEEN_CHECK(any_polygon, "{}: mesh has no triangles (only points or lines)", path);
}

// Per-face texture coordinates of a PLY (MeshLab style: a face list property `texcoord`
// with u, v per corner). assimp stores them per vertex, keeping one corner's value where
// faces disagree, which garbles textures along seams; they are read here instead.
struct PlyFaceTexcoords {
  std::vector<std::vector<int64_t>> indices;   // per face, vertex indices as in the file
  std::vector<std::vector<double>> texcoords;  // per face, u0 v0 u1 v1 ...
  bool several_textures = false;               // a `texnumber` other than 0 was seen
};

// Reads the body of a PLY before assimp does: checks that every list has at most 1e6
// entries (assimp allocates what an ASCII list count says, 32 GB for "42949672950") and
// returns the face texcoords, or std::nullopt when the faces have none. Throws naming the
// file for a header or body it cannot parse.
std::optional<PlyFaceTexcoords> ReadPlyBody(const std::string& path) {
  enum class Format { kAscii, kLittle, kBig };
  struct Property {
    std::string name;
    std::string type;        // scalar type, or list item type
    std::string count_type;  // non-empty for lists
  };
  struct Element {
    std::string name;
    int64_t count = 0;
    std::vector<Property> properties;
  };
  auto type_size = [&](const std::string& t) -> int {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" ||
        t == "float32")
      return 4;
    if (t == "double" || t == "float64") return 8;
    ThrowError("{}: PLY property type '{}' is not valid", path, t);
  };

  std::ifstream in(path, std::ios::binary);
  UNSEEN_CHECK(in.good(), "{}: cannot open", path);
  std::string line;
  Format format = Format::kAscii;
  std::vector<Element> elements;
  bool has_face_texcoords = false;
  bool header_done = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "end_header") {
      header_done = true;
      break;
    }
    if (keyword == "format") {
      std::string name;
      words >> name;
      format = name == "ascii"                  ? Format::kAscii
               : name == "binary_little_endian" ? Format::kLittle
               : name == "binary_big_endian"
                   ? Format::kBig
                   : throw Error(fmt::format("{}: unknown PLY format '{}'", path, name));
    } else if (keyword == "element") {
      Element e;
      words >> e.name >> e.count;
      UNSEEN_CHECK(!words.fail() && e.count >= 0, "{}: malformed PLY header line '{}'", path, line);
      elements.push_back(e);
    } else if (keyword == "property") {
      UNSEEN_CHECK(!elements.empty(), "{}: PLY property before any element: '{}'", path, line);
      Property p;
      std::string type;
      words >> type;
      if (type == "list") {
        words >> p.count_type >> p.type >> p.name;
        type_size(p.count_type);
      } else {
        p.type = type;
        words >> p.name;
      }
      type_size(p.type);
      UNSEEN_CHECK(!words.fail(), "{}: malformed PLY header line '{}'", path, line);
      if (elements.back().name == "face" && !p.count_type.empty() && p.name == "texcoord") {
        has_face_texcoords = true;
      }
      elements.back().properties.push_back(p);
    }
  }
  UNSEEN_CHECK(header_done, "{}: PLY header has no end_header", path);

  auto read_value = [&](const std::string& type) -> double {
    if (format == Format::kAscii) {
      double value;
      in >> value;
      UNSEEN_CHECK(!in.fail(), "{}: PLY body ends early or holds a non-number", path);
      return value;
    }
    const int size = std::clamp(type_size(type), 1, 8);
    unsigned char bytes[8] = {};
    in.read(reinterpret_cast<char*>(bytes), size);
    UNSEEN_CHECK(in.gcount() == size, "{}: PLY body ends early", path);
    if ((format == Format::kBig) == (std::endian::native == std::endian::little)) {
      std::reverse(bytes, bytes + size);
    }
    auto as = [&](auto v) {
      std::memcpy(&v, bytes, sizeof(v));
      return static_cast<double>(v);
    };
    if (type == "char" || type == "int8") return as(int8_t());
    if (type == "uchar" || type == "uint8") return as(uint8_t());
    if (type == "short" || type == "int16") return as(int16_t());
    if (type == "ushort" || type == "uint16") return as(uint16_t());
    if (type == "int" || type == "int32") return as(int32_t());
    if (type == "uint" || type == "uint32") return as(uint32_t());
    if (type == "float" || type == "float32") return as(float());
    return as(double());
  };

  PlyFaceTexcoords result;
  for (const Element& e : elements) {
    const bool is_face = e.name == "face";
    const bool fixed_size = std::all_of(e.properties.begin(), e.properties.end(),
                                        [](const Property& p) { return p.count_type.empty(); });
    if (!is_face && fixed_size && format != Format::kAscii) {  // skip in one go
      int64_t stride = 0;
      for (const Property& p : e.properties) stride += type_size(p.type);
      in.seekg(stride * e.count, std::ios::cur);
      UNSEEN_CHECK(in.good(), "{}: PLY body ends early", path);
      continue;
    }
    for (int64_t i = 0; i < e.count; ++i) {
      std::vector<int64_t> indices;
      std::vector<double> texcoords;
      for (const Property& p : e.properties) {
        if (p.count_type.empty()) {
          const double value = read_value(p.type);
          if (is_face && p.name == "texnumber" && value != 0.0) result.several_textures = true;
          continue;
        }
        const double count = read_value(p.count_type);
        UNSEEN_CHECK(count >= 0 && count <= 1e6, "{}: PLY {} {} has a list of {} entries", path,
                     e.name, i, count);
        const bool wanted_indices =
            is_face && (p.name == "vertex_indices" || p.name == "vertex_index");
        const bool wanted_texcoords = is_face && p.name == "texcoord";
        for (int k = 0; k < static_cast<int>(count); ++k) {
          const double value = read_value(p.type);
          if (wanted_indices) indices.push_back(static_cast<int64_t>(value));
          if (wanted_texcoords) texcoords.push_back(value);
        }
      }
      if (is_face && has_face_texcoords) {
        result.indices.push_back(std::move(indices));
        result.texcoords.push_back(std::move(texcoords));
      }
    }
  }
  if (!has_face_texcoords) return std::nullopt;
  return result;
}

// Gives every face corner of assimp's raw PLY mesh its own vertex carrying the face's
// texture coordinates (positions, normals and colours copied).
void ApplyPlyFaceTexcoords(const PlyFaceTexcoords& faces, const std::string& path, aiScene* scene) {
  UNSEEN_CHECK(!faces.several_textures,
               "{}: PLY faces use several textures (texnumber); only one is supported", path);
  UNSEEN_CHECK(scene->mNumMeshes == 1 && scene->mMeshes[0]->mNumFaces == faces.indices.size(),
               "{}: per-face texture coordinates do not match the faces read ({} faces in the "
               "file)",
               path, faces.indices.size());
  aiMesh& mesh = *scene->mMeshes[0];
  unsigned corners = 0;
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    UNSEEN_CHECK(
        face.mNumIndices == faces.indices[f].size() &&
            std::equal(face.mIndices, face.mIndices + face.mNumIndices, faces.indices[f].begin(),
                       [](unsigned a, int64_t b) { return int64_t(a) == b; }),
        "{}: face {} of the file does not match the face read", path, f);
    UNSEEN_CHECK(faces.texcoords[f].size() == 2 * size_t(face.mNumIndices),
                 "{}: face {} has {} texcoord values for {} corners (expected u, v per corner)",
                 path, f, faces.texcoords[f].size(), face.mNumIndices);
    corners += face.mNumIndices;
  }
  auto* vertices = new aiVector3D[corners];
  auto* uvs = new aiVector3D[corners];
  aiVector3D* normals = mesh.HasNormals() ? new aiVector3D[corners] : nullptr;
  aiColor4D* colours = mesh.HasVertexColors(0) ? new aiColor4D[corners] : nullptr;
  unsigned c = 0;
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    aiFace& face = mesh.mFaces[f];
    for (unsigned k = 0; k < face.mNumIndices; ++k, ++c) {
      const unsigned v = face.mIndices[k];
      vertices[c] = mesh.mVertices[v];
      if (normals) normals[c] = mesh.mNormals[v];
      if (colours) colours[c] = mesh.mColors[0][v];
      uvs[c] = aiVector3D(static_cast<float>(faces.texcoords[f][2 * k]),
                          static_cast<float>(faces.texcoords[f][2 * k + 1]), 0.0f);
      face.mIndices[k] = c;
    }
  }
  delete[] mesh.mVertices;
  mesh.mVertices = vertices;
  if (normals) {
    delete[] mesh.mNormals;
    mesh.mNormals = normals;
  }
  if (colours) {
    delete[] mesh.mColors[0];
    mesh.mColors[0] = colours;
  }
  for (unsigned k = 1; k < AI_MAX_NUMBER_OF_COLOR_SETS; ++k) {
    delete[] mesh.mColors[k];
    mesh.mColors[k] = nullptr;
  }
  for (unsigned k = 0; k < AI_MAX_NUMBER_OF_TEXTURECOORDS; ++k) {
    delete[] mesh.mTextureCoords[k];
    mesh.mTextureCoords[k] = nullptr;
    mesh.mNumUVComponents[k] = 0;
  }
  mesh.mTextureCoords[0] = uvs;
  mesh.mNumUVComponents[0] = 2;
  delete[] mesh.mTangents;
  mesh.mTangents = nullptr;
  delete[] mesh.mBitangents;
  mesh.mBitangents = nullptr;
  mesh.mNumVertices = corners;
}

// Merges vertices whose position and every attribute are bit-identical (assimp gives
// OBJ and glTF corners unshared) and renumbers the triangles.
void WeldIdenticalVertices(Mesh* mesh) {
  std::unordered_map<std::string, int> index;
  std::vector<int> remap(mesh->num_vertices());
  Mesh out;
  for (int v = 0; v < mesh->num_vertices(); ++v) {
    std::string key(reinterpret_cast<const char*>(mesh->vertices[v].data()), 3 * sizeof(float));
    auto append = [&](const float* data, int n) {
      key.append(reinterpret_cast<const char*>(data), n * sizeof(float));
    };
    if (!mesh->normals.empty()) append(mesh->normals[v].data(), 3);
    if (!mesh->uvs.empty()) append(mesh->uvs[v].data(), 2);
    if (!mesh->colors_bgr.empty()) append(mesh->colors_bgr[v].data(), 3);
    auto [it, inserted] = index.emplace(std::move(key), out.num_vertices());
    if (inserted) {
      out.vertices.push_back(mesh->vertices[v]);
      if (!mesh->normals.empty()) out.normals.push_back(mesh->normals[v]);
      if (!mesh->uvs.empty()) out.uvs.push_back(mesh->uvs[v]);
      if (!mesh->colors_bgr.empty()) out.colors_bgr.push_back(mesh->colors_bgr[v]);
    }
    remap[v] = it->second;
  }
  for (Eigen::Vector3i& t : mesh->triangles)
    t = Eigen::Vector3i(remap[t[0]], remap[t[1]], remap[t[2]]);
  mesh->vertices = std::move(out.vertices);
  mesh->normals = std::move(out.normals);
  mesh->uvs = std::move(out.uvs);
  mesh->colors_bgr = std::move(out.colors_bgr);
}

// ---------------------------------------------------------------------------------------
// Saving

// Material of triangle t as the renderer reads it: triangle_materials, else material 0,
// else -1 (no material).
int TriangleMaterial(const Mesh& mesh, int t) {
  if (!mesh.triangle_materials.empty()) return mesh.triangle_materials[t];
  return mesh.materials.empty() ? -1 : 0;
}

// A copy of the mesh's vertices split so that every vertex belongs to triangles of one
// material only (needed to bake per-material data into per-vertex data).
struct SplitMesh {
  std::vector<int> source;    // per new vertex: index into mesh.vertices
  std::vector<int> material;  // per new vertex: material (-1 none)
  std::vector<Eigen::Vector3i> triangles;
};

SplitMesh SplitByMaterial(const Mesh& mesh) {
  SplitMesh out;
  std::map<std::pair<int, int>, int> index;  // (vertex, material) -> new vertex
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    const int m = TriangleMaterial(mesh, t);
    Eigen::Vector3i tri;
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.triangles[t][k];
      auto [it, inserted] =
          index.emplace(std::make_pair(v, m), static_cast<int>(out.source.size()));
      if (inserted) {
        out.source.push_back(v);
        out.material.push_back(m);
      }
      tri[k] = it->second;
    }
    out.triangles.push_back(tri);
  }
  return out;
}

// Several textures packed into one image (a PLY holds one texture), with a replicated
// border around each so bilinear sampling does not bleed across tiles.
struct Atlas {
  cv::Mat image;
  // Per material: inner rectangle (without border) in the atlas, in pixels.
  std::vector<cv::Rect> tiles;
};

Atlas PackAtlas(const Mesh& mesh, const std::vector<bool>& used) {
  constexpr int kBorder = 2;
  constexpr int kSolidTile = 4;  // px, for untextured materials (their diffuse colour)
  const int n = static_cast<int>(mesh.materials.size());
  std::vector<cv::Mat> padded(n);
  double area = 0.0;
  int max_width = 0;
  for (int m = 0; m < n; ++m) {
    if (!used[m]) continue;
    const Material& mat = mesh.materials[m];
    cv::Mat tile = mat.texture;
    if (tile.empty()) {
      const Eigen::Vector3f& d = mat.diffuse_bgr;
      tile = cv::Mat(kSolidTile, kSolidTile, CV_32FC3, cv::Scalar(d[0], d[1], d[2]));
    }
    cv::copyMakeBorder(tile, padded[m], kBorder, kBorder, kBorder, kBorder, cv::BORDER_REPLICATE);
    area += double(padded[m].cols) * padded[m].rows;
    max_width = std::max(max_width, padded[m].cols);
  }
  // Shelf packing in material order, rows at most ~1.5 sqrt(area) wide.
  const int row_limit = std::max(max_width, static_cast<int>(std::ceil(1.5 * std::sqrt(area))));
  Atlas atlas;
  atlas.tiles.assign(n, cv::Rect());
  std::vector<cv::Rect> placed(n);
  int x = 0, y = 0, row_height = 0, width = 0;
  for (int m = 0; m < n; ++m) {
    if (!used[m]) continue;
    if (x > 0 && x + padded[m].cols > row_limit) {
      y += row_height;
      x = 0;
      row_height = 0;
    }
    placed[m] = cv::Rect(x, y, padded[m].cols, padded[m].rows);
    atlas.tiles[m] = cv::Rect(x + kBorder, y + kBorder, padded[m].cols - 2 * kBorder,
                              padded[m].rows - 2 * kBorder);
    x += padded[m].cols;
    row_height = std::max(row_height, padded[m].rows);
    width = std::max(width, x);
  }
  atlas.image = cv::Mat(y + row_height, width, CV_32FC3, cv::Scalar(0, 0, 0));
  for (int m = 0; m < n; ++m) {
    if (used[m]) padded[m].copyTo(atlas.image(placed[m]));
  }
  return atlas;
}

uint8_t ToByte(float c) {
  return static_cast<uint8_t>(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f));
}

template <typename T>
void WriteLittleEndian(std::ostream& out, T value) {
  static_assert(std::endian::native == std::endian::little,
                "binary PLY writing assumes a little-endian host");
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

void SavePly(const Mesh& mesh, const fs::path& path, float scale) {
  const std::string file = path.string();
  const int num_materials = static_cast<int>(mesh.materials.size());
  std::vector<bool> used(num_materials, false);
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    const int m = TriangleMaterial(mesh, t);
    if (m >= 0) used[m] = true;
  }
  int num_used = 0, num_used_textured = 0;
  for (int m = 0; m < num_materials; ++m) {
    num_used += used[m];
    num_used_textured += used[m] && !mesh.materials[m].texture.empty();
  }
  // Textures of materials no triangle uses are not saved.
  const bool textured = !mesh.uvs.empty() && num_used_textured > 0;
  // A single textured material keeps its texture and uvs as they are (repeat allowed);
  // otherwise the materials are packed into an atlas and the uvs remapped.
  const bool single_texture = textured && num_used == 1;
  const bool atlas_needed = textured && !single_texture;
  // Without texture or vertex colours, distinct material colours become vertex colours.
  bool bake_diffuse = false;
  if (!textured && mesh.colors_bgr.empty()) {
    for (int m = 0; m < num_materials; ++m) {
      if (used[m] && !mesh.materials[m].diffuse_bgr.isApprox(Eigen::Vector3f::Ones())) {
        bake_diffuse = true;
      }
    }
  }

  SplitMesh split;
  if (atlas_needed || bake_diffuse) {
    split = SplitByMaterial(mesh);
  } else {
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      split.source.push_back(v);
      split.material.push_back(-1);
    }
    split.triangles = mesh.triangles;
  }
  const int n = static_cast<int>(split.source.size());

  std::vector<Eigen::Vector2f> uvs;
  std::string texture_name;
  if (textured) {
    texture_name = path.stem().string() + ".png";
    uvs.resize(n);
    if (single_texture) {
      int m = 0;
      while (!used[m]) ++m;
      SaveColorImage((path.parent_path() / texture_name).string(), mesh.materials[m].texture);
      for (int i = 0; i < n; ++i) uvs[i] = mesh.uvs[split.source[i]];
    } else {
      const Atlas atlas = PackAtlas(mesh, used);
      SaveColorImage((path.parent_path() / texture_name).string(), atlas.image);
      const float w = static_cast<float>(atlas.image.cols);
      const float h = static_cast<float>(atlas.image.rows);
      for (int i = 0; i < n; ++i) {
        const int m = split.material[i];
        Eigen::Vector2f uv(0.5f, 0.5f);  // untextured material: centre of its solid tile
        if (m >= 0 && !mesh.materials[m].texture.empty()) {
          uv = mesh.uvs[split.source[i]];
          constexpr float kTolerance = 1e-3f;
          UNSEEN_CHECK((uv.array() >= -kTolerance).all() && (uv.array() <= 1.0f + kTolerance).all(),
                       "{}: vertex {} has uv ({}, {}) outside [0, 1]; a PLY holds one texture, "
                       "so repeating textures of several materials cannot be packed; save as .obj",
                       file, split.source[i], uv.x(), uv.y());
          uv = uv.cwiseMax(0.0f).cwiseMin(1.0f);
        }
        const cv::Rect& tile = m >= 0 ? atlas.tiles[m] : cv::Rect(0, 0, 1, 1);
        const float col = tile.x + uv.x() * tile.width;
        const float row = tile.y + (1.0f - uv.y()) * tile.height;
        uvs[i] = Eigen::Vector2f(col / w, 1.0f - row / h);
      }
    }
  }

  std::vector<Eigen::Vector3f> colours;
  if (!mesh.colors_bgr.empty()) {
    for (int i = 0; i < n; ++i) colours.push_back(mesh.colors_bgr[split.source[i]]);
  } else if (bake_diffuse) {
    for (int i = 0; i < n; ++i) {
      colours.push_back(split.material[i] >= 0 ? mesh.materials[split.material[i]].diffuse_bgr
                                               : Eigen::Vector3f::Ones());
    }
  }
  const bool has_normals = !mesh.normals.empty();

  std::ofstream out(path, std::ios::binary);
  UNSEEN_CHECK(out.good(), "{}: cannot open for writing", file);
  out << "ply\nformat binary_little_endian 1.0\ncomment written by unseen\n";
  if (textured) out << "comment TextureFile " << texture_name << "\n";
  out << "element vertex " << n << "\n"
      << "property float x\nproperty float y\nproperty float z\n";
  if (has_normals) out << "property float nx\nproperty float ny\nproperty float nz\n";
  if (!colours.empty()) out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (textured) out << "property float texture_u\nproperty float texture_v\n";
  out << "element face " << split.triangles.size() << "\n"
      << "property list uchar int vertex_indices\nend_header\n";
  for (int i = 0; i < n; ++i) {
    const int s = split.source[i];
    const Eigen::Vector3f p = mesh.vertices[s] * scale;
    for (int k = 0; k < 3; ++k) WriteLittleEndian<float>(out, p[k]);
    if (has_normals) {
      for (int k = 0; k < 3; ++k) WriteLittleEndian<float>(out, mesh.normals[s][k]);
    }
    if (!colours.empty()) {
      for (int k = 2; k >= 0; --k) WriteLittleEndian<uint8_t>(out, ToByte(colours[i][k]));  // RGB
    }
    if (textured) {
      WriteLittleEndian<float>(out, uvs[i].x());
      WriteLittleEndian<float>(out, uvs[i].y());
    }
  }
  for (const Eigen::Vector3i& tri : split.triangles) {
    WriteLittleEndian<uint8_t>(out, 3);
    for (int k = 0; k < 3; ++k) WriteLittleEndian<int32_t>(out, tri[k]);
  }
  UNSEEN_CHECK(out.good(), "{}: write failed", file);
}

// A material name usable in MTL files and file names: [A-Za-z0-9_+-.] only.
std::string SanitiseName(const std::string& name) {
  std::string out;
  for (char c : name) {
    const bool ok =
        std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '+' || c == '.';
    out.push_back(ok ? c : '_');
  }
  return out.empty() ? "material" : out;
}

void SaveObj(const Mesh& mesh, const fs::path& path, float scale) {
  const std::string file = path.string();
  const std::string stem = path.stem().string();
  const fs::path dir = path.parent_path();
  const std::string mtl_name = stem + ".mtl";

  // Materials: the mesh's, or one white default when it has none.
  std::vector<Material> materials = mesh.materials;
  if (materials.empty()) {
    Material m;
    m.name = "default";
    materials.push_back(m);
  }
  std::vector<std::string> names;
  std::set<std::string> taken;
  for (size_t m = 0; m < materials.size(); ++m) {
    std::string name = SanitiseName(materials[m].name);
    while (taken.count(name)) name = fmt::format("{}_{}", name, m);
    taken.insert(name);
    names.push_back(name);
  }
  {
    std::ofstream mtl(dir / mtl_name);
    UNSEEN_CHECK(mtl.good(), "{}: cannot open for writing", (dir / mtl_name).string());
    mtl << "# written by unseen\n";
    for (size_t m = 0; m < materials.size(); ++m) {
      const Eigen::Vector3f& d = materials[m].diffuse_bgr;
      mtl << "\nnewmtl " << names[m] << "\n"
          << "Ka 0 0 0\nKd " << d[2] << " " << d[1] << " " << d[0] << "\nKs 0 0 0\nd 1\nillum 1\n";
      if (!materials[m].texture.empty()) {
        const std::string texture_name = stem + "_" + names[m] + ".png";
        SaveColorImage((dir / texture_name).string(), materials[m].texture);
        mtl << "map_Kd " << texture_name << "\n";
      }
    }
    UNSEEN_CHECK(mtl.good(), "{}: write failed", (dir / mtl_name).string());
  }

  std::ofstream out(path);
  UNSEEN_CHECK(out.good(), "{}: cannot open for writing", file);
  out.precision(9);
  out << "# written by unseen\nmtllib " << mtl_name << "\no " << SanitiseName(stem) << "\n";
  const bool has_colours = !mesh.colors_bgr.empty();
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3f p = mesh.vertices[v] * scale;
    out << "v " << p.x() << " " << p.y() << " " << p.z();
    if (has_colours) {  // the common "v x y z r g b" extension
      const Eigen::Vector3f& c = mesh.colors_bgr[v];
      out << " " << c[2] << " " << c[1] << " " << c[0];
    }
    out << "\n";
  }
  const bool has_uvs = !mesh.uvs.empty();
  const bool has_normals = !mesh.normals.empty();
  for (const Eigen::Vector2f& uv : mesh.uvs) out << "vt " << uv.x() << " " << uv.y() << "\n";
  for (const Eigen::Vector3f& n : mesh.normals) {
    out << "vn " << n.x() << " " << n.y() << " " << n.z() << "\n";
  }
  // Faces grouped by material, in material order.
  std::vector<std::vector<int>> by_material(materials.size());
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    by_material[std::max(0, TriangleMaterial(mesh, t))].push_back(t);
  }
  for (size_t m = 0; m < materials.size(); ++m) {
    if (by_material[m].empty()) continue;
    out << "usemtl " << names[m] << "\n";
    for (int t : by_material[m]) {
      out << "f";
      for (int k = 0; k < 3; ++k) {
        const int i = mesh.triangles[t][k] + 1;  // OBJ indices start at 1
        out << " " << i;
        if (has_uvs && has_normals) {
          out << "/" << i << "/" << i;
        } else if (has_uvs) {
          out << "/" << i;
        } else if (has_normals) {
          out << "//" << i;
        }
      }
      out << "\n";
    }
  }
  UNSEEN_CHECK(out.good(), "{}: write failed", file);
}

void SaveProjectors(const Mesh& mesh, const fs::path& mesh_path, float scale) {
  const fs::path json_path = ProjectorsPath(mesh_path);
  std::error_code ec;
  if (mesh.projectors.empty()) {
    fs::remove(json_path, ec);  // a stale file would be read back by LoadMesh
    return;
  }
  json list = json::array();
  for (size_t i = 0; i < mesh.projectors.size(); ++i) {
    const Projector& p = mesh.projectors[i];
    const std::string image_name =
        fmt::format("{}_projector_{:03d}.png", mesh_path.stem().string(), i);
    SaveColorImage((mesh_path.parent_path() / image_name).string(), p.image);
    const Eigen::Matrix3d r = p.cam_from_obj.RotationMatrix();
    const Eigen::Vector3d t = p.cam_from_obj.translation() * static_cast<double>(scale);
    json camera = {{"width", p.camera.width},
                   {"height", p.camera.height},
                   {"fx", p.camera.fx},
                   {"fy", p.camera.fy},
                   {"cx", p.camera.cx},
                   {"cy", p.camera.cy},
                   {"distortion", p.camera.distortion}};
    json pose = {
        {"rotation",
         {{r(0, 0), r(0, 1), r(0, 2)}, {r(1, 0), r(1, 1), r(1, 2)}, {r(2, 0), r(2, 1), r(2, 2)}}},
        {"translation", {t.x(), t.y(), t.z()}}};
    list.push_back({{"image", image_name}, {"camera", camera}, {"cam_from_obj", pose}});
  }
  json root = {
      {"comment", "Projective textures of " + mesh_path.filename().string() +
                      ": image, pinhole intrinsics (pixels, pixel-centre origin) and "
                      "cam_from_obj (rotation row-major, translation in the mesh file's units)"},
      {"projectors", list}};
  std::ofstream out(json_path);
  UNSEEN_CHECK(out.good(), "{}: cannot open for writing", json_path.string());
  out << root.dump(1) << "\n";
  UNSEEN_CHECK(out.good(), "{}: write failed", json_path.string());
}

}  // namespace

Mesh LoadMesh(const std::string& path, double scale_to_metres) {
  UNSEEN_CHECK(std::isfinite(scale_to_metres) && scale_to_metres > 0.0,
               "{}: scale_to_metres must be positive and finite, got {}", path, scale_to_metres);
  std::error_code ec;
  UNSEEN_CHECK(fs::is_regular_file(path, ec), "{}: mesh file not found", path);

  const std::string extension = LowerExtension(path);
  std::optional<PlyFaceTexcoords> ply_face_texcoords;
  if (extension == ".ply") {
    CheckPlyHeader(path);
    ply_face_texcoords = ReadPlyBody(path);
  }
  if (extension == ".obj") CheckObjIndices(path);
  if (extension == ".dae" || extension == ".xml") CheckColladaText(path);
  if (extension == ".gltf" || extension == ".glb") CheckGltfText(path, extension == ".glb");

  Assimp::Importer importer;
  // The object frame is the file's own coordinates: no Collada Z-up -> Y-up rotation.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  // Drop points and lines; keep triangles (polygons are triangulated).
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
  UNSEEN_CHECK(scene != nullptr, "{}: cannot read mesh: {}", path, importer.GetErrorString());
  // assimp's post-processing asserts (aborts) on some malformed data that its validation
  // lets through, e.g. faces without indices: check the raw data first.
  CheckRawScene(*scene, path);
  if (ply_face_texcoords) {
    // The scene is the importer's to modify until post-processing.
    ApplyPlyFaceTexcoords(*ply_face_texcoords, path, const_cast<aiScene*>(scene));
  }
  // (No aiProcess_JoinIdenticalVertices: assimp 5.2 merges vertices whose colours differ;
  // WeldIdenticalVertices does it afterwards.)
  scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_PreTransformVertices |
                                       aiProcess_SortByPType);
  UNSEEN_CHECK(scene != nullptr, "{}: cannot process mesh: {}", path, importer.GetErrorString());
  UNSEEN_CHECK(scene->mNumMeshes > 0 && !(scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE),
               "{}: mesh has no triangles", path);

  Mesh mesh;
  TextureLoader textures(scene, path);
  std::map<unsigned, int> material_index;  // assimp material -> ours (used ones only)
  bool all_normals = true, any_uvs = false, any_colours = false;
  std::vector<int> vertex_material;  // per vertex, to fill colours of uncoloured sub-meshes
  std::vector<bool> vertex_has_colour;
  for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) {
    const aiMesh& sub = *scene->mMeshes[mi];
    if (!(sub.mPrimitiveTypes & aiPrimitiveType_TRIANGLE) || sub.mNumFaces == 0) continue;
    int material = -1;
    if (sub.mMaterialIndex < scene->mNumMaterials) {
      auto it = material_index.find(sub.mMaterialIndex);
      if (it == material_index.end()) {
        mesh.materials.push_back(ConvertMaterial(*scene, sub.mMaterialIndex, &textures));
        const int ours = static_cast<int>(mesh.materials.size()) - 1;
        it = material_index.emplace(sub.mMaterialIndex, ours).first;
      }
      material = it->second;
    }
    const int base = mesh.num_vertices();
    const bool has_uvs = sub.HasTextureCoords(0);
    const bool has_colours = sub.HasVertexColors(0);
    all_normals = all_normals && sub.HasNormals();
    any_uvs = any_uvs || has_uvs;
    any_colours = any_colours || has_colours;
    for (unsigned v = 0; v < sub.mNumVertices; ++v) {
      const aiVector3D& p = sub.mVertices[v];
      mesh.vertices.emplace_back(p.x, p.y, p.z);
      if (sub.HasNormals()) {
        const aiVector3D& n = sub.mNormals[v];
        mesh.normals.emplace_back(n.x, n.y, n.z);
      } else {
        mesh.normals.emplace_back(0.0f, 0.0f, 0.0f);
      }
      if (has_uvs) {
        mesh.uvs.emplace_back(sub.mTextureCoords[0][v].x, sub.mTextureCoords[0][v].y);
      } else {
        mesh.uvs.emplace_back(0.0f, 0.0f);
      }
      if (has_colours) {
        const aiColor4D& c = sub.mColors[0][v];
        mesh.colors_bgr.push_back(Eigen::Vector3f(c.b, c.g, c.r).cwiseMax(0.0f).cwiseMin(1.0f));
      } else {
        mesh.colors_bgr.emplace_back(1.0f, 1.0f, 1.0f);
      }
      vertex_material.push_back(material);
      vertex_has_colour.push_back(has_colours);
    }
    for (unsigned f = 0; f < sub.mNumFaces; ++f) {
      const aiFace& face = sub.mFaces[f];
      if (face.mNumIndices != 3) continue;
      for (unsigned k = 0; k < 3; ++k) {
        UNSEEN_CHECK(face.mIndices[k] < sub.mNumVertices,
                     "{}: sub-mesh {} face {} has vertex index {} out of range [0, {})", path, mi,
                     f, face.mIndices[k], sub.mNumVertices);
      }
      mesh.triangles.emplace_back(base + static_cast<int>(face.mIndices[0]),
                                  base + static_cast<int>(face.mIndices[1]),
                                  base + static_cast<int>(face.mIndices[2]));
      mesh.triangle_materials.push_back(material);
    }
  }
  UNSEEN_CHECK(!mesh.triangles.empty(), "{}: mesh has no triangles", path);

  if (!all_normals) mesh.normals.clear();
  for (Eigen::Vector3f& n : mesh.normals) {  // node transforms may have scaled them
    const float length = n.norm();
    if (!(length > 0.0f && std::isfinite(length))) {  // unusable: drop (computed on need)
      mesh.normals.clear();
      break;
    }
    n /= length;
  }
  if (!any_uvs) mesh.uvs.clear();
  if (any_colours) {  // sub-meshes without colours take their material's colour
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if (!vertex_has_colour[v] && vertex_material[v] >= 0) {
        mesh.colors_bgr[v] = mesh.materials[vertex_material[v]].diffuse_bgr;
      }
    }
  } else {
    mesh.colors_bgr.clear();
  }
  if (std::any_of(mesh.triangle_materials.begin(), mesh.triangle_materials.end(),
                  [](int m) { return m < 0; })) {
    // Some triangles without material: give them a white one so indices stay valid.
    Material white;
    white.name = "default";
    const int index = static_cast<int>(mesh.materials.size());
    mesh.materials.push_back(white);
    for (int& m : mesh.triangle_materials) {
      if (m < 0) m = index;
    }
  }

  WeldIdenticalVertices(&mesh);

  // BOP-style PLY: the texture is named in a header comment, not in a material.
  if (extension == ".ply" && !mesh.uvs.empty()) {
    const std::string texture_file = ReadPlyTextureComment(path);
    if (!texture_file.empty()) {
      TextureLoader files(nullptr, path);
      const cv::Mat texture = files.Load(texture_file);
      for (Material& m : mesh.materials) {
        if (m.texture.empty()) {
          m.texture = texture;
          m.texture_path = texture_file;
        }
      }
    }
  }

  const fs::path projectors_path = ProjectorsPath(path);
  if (fs::is_regular_file(projectors_path, ec)) mesh.projectors = ReadProjectors(projectors_path);

  mesh.Scale(static_cast<float>(scale_to_metres));
  mesh.Check(path);
  return mesh;
}

void SaveMesh(const Mesh& mesh, const std::string& path, double scale_from_metres) {
  UNSEEN_CHECK(std::isfinite(scale_from_metres) && scale_from_metres > 0.0,
               "{}: scale_from_metres must be positive and finite, got {}", path,
               scale_from_metres);
  mesh.Check(path);
  const fs::path file(path);
  const std::string ext = LowerExtension(file);
  UNSEEN_CHECK(ext == ".ply" || ext == ".obj", "{}: cannot save a mesh as '{}'; use .ply or .obj",
               path, ext);
  if (file.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(file.parent_path(), ec);
    UNSEEN_CHECK(!ec, "{}: cannot create folder '{}': {}", path, file.parent_path().string(),
                 ec.message());
  }
  const float scale = static_cast<float>(scale_from_metres);
  if (ext == ".ply") {
    SavePly(mesh, file, scale);
  } else {
    SaveObj(mesh, file, scale);
  }
  SaveProjectors(mesh, file, scale);
}

}  // namespace unseen
