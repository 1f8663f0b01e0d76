// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/mesh/mesh_file_checks.h"

#include <assimp/BaseImporter.h>
#include <assimp/mesh.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "unseen/util/error.h"

namespace unseen::mesh_checks {
namespace fs = std::filesystem;

std::string Trim(const std::string& s) {
  const size_t first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t\r\n") + 1 - first);
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
    // assimp separates words by spaces and tabs only: another control character (a
    // vertical tab) would join what the split above separates ("vertex_indices\v").
    const bool plain = std::none_of(line.begin(), line.end(), [](unsigned char c) {
      return (c < 0x20 && c != '\t') || c == 0x7f;
    });
    bool valid = false;
    if (!plain && keyword != "comment" && keyword != "obj_info") {
      valid = false;
    } else if (n == 1) {
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

namespace {

// OBJ: assimp crashes on face corners that refer to normals (or uvs) the file does not
// have. Every index of the f, l and p lines is checked: positive ones against the file's
// counts of v, vt and vn, negative (relative) ones against those read so far.

void CheckObjIndices(const std::string& path, const std::string& text) {
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
            !index.empty() && *end == '\0' && i != 0 && (i > 0 ? i <= total[k] : i >= -so_far[k]);
        UNSEEN_CHECK(valid, "{}: line {}: '{}' refers to {} {}, but the file has {}", path, n,
                     line.substr(0, 80), kNames[k], index, total[k]);
      }
      UNSEEN_CHECK(start > corner.size(), "{}: line {}: '{}' is not v/vt/vn", path, n, corner);
    }
  });
}

// OBJ materials: assimp 5.2 writes a material statement (map_Kd, Kd, ...) that comes before
// the first newmtl of a library through a null pointer. It reads the libraries the mtllib
// lines name and, when one is missing, <stem>.mtl beside the OBJ; each of those that exists
// may hold only comments and blank lines before its first newmtl.
void CheckObjMaterials(const std::string& path, const std::string& text) {
  const fs::path obj(path);
  std::vector<fs::path> libraries = {obj.parent_path() / (obj.stem().string() + ".mtl")};
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword != "mtllib") continue;
    std::string rest;
    std::getline(words, rest);
    rest = Trim(rest.substr(0, rest.find('#')));
    if (!rest.empty()) libraries.push_back(obj.parent_path() / rest);
  }
  for (const fs::path& library : libraries) {
    std::error_code ec;
    if (!fs::is_regular_file(library, ec)) continue;
    std::istringstream text(ReadText(library.string()));
    for (int n = 1; std::getline(text, line); ++n) {
      const std::string statement = Trim(line.substr(0, line.find('#')));
      if (statement.empty()) continue;
      std::istringstream words(statement);
      std::string keyword;
      words >> keyword;
      if (keyword == "newmtl") break;
      ThrowError("{}: line {}: '{}' comes before any newmtl (material library of {})",
                 library.string(), n, statement.substr(0, 80), path);
    }
  }
}

}  // namespace

void CheckObjFile(const std::string& path) {
  const std::string text = ReadText(path);
  CheckObjIndices(path, text);
  CheckObjMaterials(path, text);
}

namespace {

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

// Position just after `<name> =` in `text` at `at` (where the name starts), or npos when no
// attribute of that name starts there.
size_t AfterAttribute(std::string_view text, size_t at, std::string_view name) {
  if (at == 0 || !IsBlank(text[at - 1])) return std::string::npos;  // <vcount>, "account", ...
  size_t i = at + name.size();
  while (i < text.size() && IsBlank(text[i])) ++i;
  if (i >= text.size() || text[i] != '=') return std::string::npos;
  return i + 1;
}

// The value of the attribute `name` starting at `at` in `text`, trimmed, or std::nullopt
// when no quoted attribute of that name starts there.
std::optional<std::string> AttributeValue(std::string_view text, size_t at,
                                          std::string_view name) {
  size_t i = AfterAttribute(text, at, name);
  if (i == std::string::npos) return std::nullopt;
  while (i < text.size() && IsBlank(text[i])) ++i;
  if (i >= text.size() || (text[i] != '"' && text[i] != '\'')) return std::nullopt;
  const size_t close = text.find(text[i], i + 1);
  if (close == std::string::npos) return std::nullopt;
  return Trim(std::string(text.substr(i + 1, close - i - 1)));
}

// Whether `value` is a decimal or 0x-hexadecimal number, as assimp's XML reader takes them
// (a sign wraps around), of at most `limit`.
bool IsNumberUpTo(const std::string& value, size_t limit) {
  const bool hex = value.rfind("0x", 0) == 0 || value.rfind("0X", 0) == 0;
  const std::string digits = hex ? value.substr(2) : value;
  const bool plain = !digits.empty() && digits.size() <= 12 &&
                     std::all_of(digits.begin(), digits.end(), [&](unsigned char c) {
                       return hex ? std::isxdigit(c) != 0 : std::isdigit(c) != 0;
                     });
  return plain && std::stoull(digits, nullptr, hex ? 16 : 10) <= limit;
}

// Whether the integer part of the decimal number that starts `token` (after a sign) is at
// most 2^64 - 1. assimp reads a number's integer part as a 64-bit integer and, when it
// overflows, returns 0 without moving on: the next value is read from the same digits
// (in a PLY file, a list count taken from a coordinate: a 13 GB allocation).
bool IntegerPartFitsUint64(const std::string& token) {
  size_t i = token.empty() || (token[0] != '-' && token[0] != '+') ? 0 : 1;
  while (i < token.size() && token[i] == '0') ++i;
  const size_t first = i;
  while (i < token.size() && std::isdigit(static_cast<unsigned char>(token[i]))) ++i;
  const std::string digits = token.substr(first, i - first);
  static const std::string kMax = "18446744073709551615";
  return digits.size() < kMax.size() || (digits.size() == kMax.size() && digits <= kMax);
}

// The range of a PLY integer type; +-infinity for the floating-point types.
std::pair<double, double> IntegerRange(const std::string& type) {
  if (type == "char" || type == "int8") return {-128.0, 127.0};
  if (type == "uchar" || type == "uint8") return {0.0, 255.0};
  if (type == "short" || type == "int16") return {-32768.0, 32767.0};
  if (type == "ushort" || type == "uint16") return {0.0, 65535.0};
  if (type == "int" || type == "int32") return {-2147483648.0, 2147483647.0};
  if (type == "uint" || type == "uint32") return {0.0, 4294967295.0};
  const double inf = std::numeric_limits<double>::infinity();
  return {-inf, inf};
}


// Calls fn(body) for each element of `text` opened by `open` ("<p", "<polylist") and not
// self-closing, `body` the offset just after its opening tag's '>'.
template <typename Fn>
void ForEachElementBody(const std::string& text, std::string_view open, Fn&& fn) {
  for (size_t at = text.find(open); at != std::string::npos; at = text.find(open, at + 1)) {
    const size_t name_end = at + open.size();
    if (name_end >= text.size() || (text[name_end] != '>' && !IsBlank(text[name_end]))) continue;
    const size_t open_end = text.find('>', name_end);
    if (open_end == std::string::npos || text[open_end - 1] == '/') continue;
    fn(open_end + 1);
  }
}

}  // namespace

// Collada: a <p> index list holding anything but integers and blanks makes assimp loop for
// ever, a data array without a count attribute or with count="0" makes it dereference a
// null pointer, a count="N" attribute or a polygon size in <vcount> has it reserve memory
// for N values before it looks at them, and a huge stride or offset overflows its index
// arithmetic. These numbers are checked against the file's size (every value takes at
// least a byte), so that a short file cannot ask for gigabytes.
void CheckColladaText(const std::string& path) {
  const std::string text = ReadText(path);
  for (const char* array : {"<float_array", "<int_array", "<bool_array", "<Name_array",
                            "<IDREF_array", "<SIDREF_array", "<token_array"}) {
    for (size_t at = text.find(array); at != std::string::npos; at = text.find(array, at + 1)) {
      const std::string_view tag =
          std::string_view(text).substr(at, text.find('>', at) - at);  // to the end if no '>'
      std::optional<std::string> count;
      for (size_t c = tag.find("count"); c != std::string::npos && !count;
           c = tag.find("count", c + 1)) {
        count = AttributeValue(tag, c, "count");
      }
      UNSEEN_CHECK(count, "{}: {}> element without a count attribute", path, array);
      // An empty array makes assimp dereference a null pointer when it is read.
      UNSEEN_CHECK(count->find_first_not_of("0xX") != std::string::npos,
                   "{}: {}> element with count=\"{}\": no values", path, array, *count);
    }
  }
  for (const std::string_view name : {"count", "stride", "offset"}) {
    for (size_t at = text.find(name); at != std::string::npos; at = text.find(name, at + 1)) {
      const std::optional<std::string> value = AttributeValue(text, at, name);
      UNSEEN_CHECK(!value || IsNumberUpTo(*value, text.size()),
                   "{}: {}=\"{}\" is not a number of values the file can hold ({} bytes)", path,
                   name, *value, text.size());
    }
  }
  // A <polylist> without its polygon sizes makes assimp dereference a null pointer.
  ForEachElementBody(text, "<polylist", [&](size_t body) {
    const size_t end = std::min(text.find("</polylist", body), text.size());
    const size_t sizes = text.find("<vcount>", body);
    UNSEEN_CHECK(sizes != std::string::npos && sizes < end,
                 "{}: <polylist> without a <vcount> element (its polygon sizes)", path);
  });
  // Polygon sizes: assimp reserves what they say.
  for (size_t at = text.find("<vcount>"); at != std::string::npos;
       at = text.find("<vcount>", at + 1)) {
    const size_t begin = at + 8, end = std::min(text.find('<', begin), text.size());
    std::istringstream sizes(text.substr(begin, end - begin));
    std::string size;
    while (sizes >> size) {
      UNSEEN_CHECK(IsNumberUpTo(size, text.size()),
                   "{}: <vcount> holds '{}', not a polygon size the file can hold ({} bytes)",
                   path, size.substr(0, 20), text.size());
    }
  }
  ForEachElementBody(text, "<p", [&](size_t body) {
    const size_t end = std::min(text.find('<', body), text.size());
    const std::string list = text.substr(body, end - body);
    const size_t bad = list.find_first_not_of("0123456789+- \t\r\n");
    UNSEEN_CHECK(bad == std::string::npos,
                 "{}: <p> index list holds '{}', expected integers separated by blanks", path,
                 list.substr(bad, 20));
  });
}

// glTF: assimp parses the JSON recursively, so that deeply nested input exhausts the
// stack, allocates what a .glb file's header says before it reads it, and takes an image's
// file extension from after the '/' of its media type without checking there is one (a
// "data:png;base64,..." URI or "mimeType": "png" crashes it). The nesting of a .gltf file,
// or of a .glb file's JSON chunk, the lengths in a .glb header and the media types are
// checked first.
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
  // The string starting at `at` (after its opening quote), up to its closing quote.
  const auto string_at = [&](size_t at) {
    size_t end = at;
    while (end < json.size() && json[end] != '"') end += json[end] == '\\' ? 2 : 1;
    return json.substr(at, std::min(end, json.size()) - at);
  };
  const auto check_media_type = [&](std::string_view type, std::string_view where) {
    UNSEEN_CHECK(type.empty() || type.find('/') != std::string_view::npos,
                 "{}: {} has media type '{}', expected type/subtype (e.g. image/png)", path,
                 where, type.substr(0, 40));
  };
  for (size_t at = json.find("\"data:"); at != std::string_view::npos;
       at = json.find("\"data:", at + 1)) {
    const std::string_view uri = string_at(at + 1);
    const std::string_view type = uri.substr(5, uri.find_first_of(";,", 5) - 5);
    check_media_type(type, "a data: URI");
  }
  for (size_t at = json.find("\"mimeType\""); at != std::string_view::npos;
       at = json.find("\"mimeType\"", at + 1)) {
    size_t i = at + 10;
    while (i < json.size() && (IsBlank(json[i]) || json[i] == ':')) ++i;
    if (i < json.size() && json[i] == '"') check_media_type(string_at(i + 1), "a mimeType");
  }
}

void CheckImporterForExtension(const Assimp::Importer& importer, const std::string& path) {
  std::string lower = path;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  std::vector<Assimp::BaseImporter*> claiming;
  for (size_t i = 0; i < importer.GetImporterCount(); ++i) {
    Assimp::BaseImporter* candidate = importer.GetImporter(i);
    if (candidate == nullptr) continue;
    std::set<std::string> extensions;
    candidate->GetExtensionList(extensions);
    for (const std::string& extension : extensions) {  // the whole ending: "mesh.xml"
      const std::string ending = "." + extension;
      if (lower.size() >= ending.size() &&
          lower.compare(lower.size() - ending.size(), ending.size(), ending) == 0) {
        claiming.push_back(candidate);
        break;
      }
    }
  }
  UNSEEN_CHECK(!claiming.empty(), "{}: no mesh format has this file's extension", path);
  if (claiming.size() == 1) return;  // assimp takes it without guessing
  for (const Assimp::BaseImporter* candidate : claiming) {
    try {
      if (candidate->CanRead(path, importer.GetIOHandler(), true)) return;
    } catch (...) {  // a malformed file some importers' checks throw on: not theirs
    }
  }
  ThrowError("{}: not a file of the format its extension names (no reader for it recognises it)",
             path);
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

// Reads the body of a PLY before assimp does: checks that every list has at most 1e6
// entries (assimp allocates what an ASCII list count says, 32 GB for "42949672950"), that
// every value fits its type, and
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

  // ASCII: each element instance is one line, as assimp parses them, so that a value is
  // checked as the property assimp will read it as.
  std::istringstream instance;
  auto next_instance = [&](const Element& e, int64_t i) {
    std::string text;
    UNSEEN_CHECK(std::getline(in, text), "{}: PLY body ends early, at {} {}", path, e.name, i);
    if (!text.empty() && text.back() == '\r') text.pop_back();
    // A control character (a NUL above all) ends or splits assimp's reading of the line
    // differently from this one: its lists then take their counts from other values.
    const auto control = std::find_if(text.begin(), text.end(), [](char c) {
      return static_cast<unsigned char>(c) < 0x20 && c != '\t';
    });
    UNSEEN_CHECK(control == text.end(), "{}: PLY {} {} holds a control character (code {})", path,
                 e.name, i, control == text.end() ? 0 : int(static_cast<unsigned char>(*control)));
    instance.clear();
    instance.str(text);
  };
  auto read_value = [&](const std::string& type) -> double {
    if (format == Format::kAscii) {
      const std::streampos at = instance.tellg();
      std::string token;
      if (instance >> token) {
        UNSEEN_CHECK(IntegerPartFitsUint64(token),
                     "{}: PLY value '{}' has an integer part beyond 64 bits", path,
                     token.substr(0, 40));
        instance.seekg(at);
      }
      double value;
      instance >> value;
      UNSEEN_CHECK(!instance.fail(),
                   "{}: PLY line '{}' holds a non-number or fewer values than its element's "
                   "properties",
                   path, instance.str().substr(0, 80));
      // assimp reads an integer property's digits up to the first other character: a value
      // such as "8446744070739.1e-320616" (0 as a number) is a list of 8e12 entries to it.
      if (IntegerRange(type).second < std::numeric_limits<double>::infinity()) {
        instance.seekg(at);
        std::string token;
        instance >> token;
        const size_t first_digit = token.find_first_not_of("+-");
        UNSEEN_CHECK(first_digit != std::string::npos &&
                         token.find_first_not_of("0123456789", first_digit) == std::string::npos,
                     "{}: PLY value '{}' of integer type {} is not an integer", path,
                     token.substr(0, 40), type);
      }
      // assimp converts integers with wrap-around: a count or index beyond its type's range
      // becomes an arbitrary (e.g. gigabyte) size.
      const auto [lo, hi] = IntegerRange(type);
      UNSEEN_CHECK(!(value < lo || value > hi), "{}: PLY value {} does not fit its type {}", path,
                   value, type);
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
      if (format == Format::kAscii) next_instance(e, i);
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

}  // namespace unseen::mesh_checks
