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
#include "unseen/mesh/mesh_file_checks.h"
#include "unseen/mesh/projector_io.h"
#include "unseen/util/error.h"
#include "unseen/util/files.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;
using namespace mesh_checks;

std::string LowerExtension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// ---------------------------------------------------------------------------------------
// Loading

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

// An assimp colour as BGR clamped to [0, 1]; its callers reject colours that are not numbers.
Eigen::Vector3f ClampedBgr(const aiColor4D& colour) {
  return Eigen::Vector3f(colour.b, colour.g, colour.r).cwiseMax(0.0f).cwiseMin(1.0f);
}

bool HasNaN(const aiColor4D& colour) {
  return std::isnan(colour.r) || std::isnan(colour.g) || std::isnan(colour.b);
}

// Converts assimp material `index` to a Material with its diffuse colour and texture.
Material ConvertMaterial(const aiScene& scene, unsigned index, TextureLoader* textures,
                         const std::string& path) {
  const aiMaterial& in = *scene.mMaterials[index];
  Material out;
  aiString name;
  if (in.Get(AI_MATKEY_NAME, name) == AI_SUCCESS) out.name = name.C_Str();
  if (out.name.empty()) out.name = "material_" + std::to_string(index);
  aiColor4D colour;
  if (in.Get(AI_MATKEY_COLOR_DIFFUSE, colour) == AI_SUCCESS ||
      in.Get(AI_MATKEY_BASE_COLOR, colour) == AI_SUCCESS) {
    UNSEEN_CHECK(!HasNaN(colour), "{}: material '{}' has diffuse colour (r g b) = ({} {} {})",
                 path, out.name, colour.r, colour.g, colour.b);
    out.diffuse_bgr = ClampedBgr(colour);
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


// Merges vertices whose position and every attribute are bit-identical (assimp gives
// OBJ and glTF corners unshared) and renumbers the triangles.
void WeldIdenticalVertices(Mesh* mesh) {
  std::unordered_map<std::string, int> index;
  std::vector<int> remap(mesh->num_vertices());
  Mesh out;
  for (int v = 0; v < mesh->num_vertices(); ++v) {
    std::string key;
    key.reserve(11 * sizeof(float));  // position, normal, uv, colour
    auto append = [&](const float* data, int n) {
      key.append(reinterpret_cast<const char*>(data), n * sizeof(float));
    };
    append(mesh->vertices[v].data(), 3);
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
  if (extension == ".obj") CheckObjFile(path);
  if (extension == ".dae" || extension == ".xml") CheckColladaText(path);
  if (extension == ".gltf" || extension == ".glb") CheckGltfText(path, extension == ".glb");

  Assimp::Importer importer;
  // The object frame is the file's own coordinates: no Collada Z-up -> Y-up rotation.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  // Drop points and lines; keep triangles (polygons are triangulated).
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  CheckImporterForExtension(importer, path);
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
        mesh.materials.push_back(ConvertMaterial(*scene, sub.mMaterialIndex, &textures, path));
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
        UNSEEN_CHECK(!HasNaN(c), "{}: sub-mesh {} vertex {} has colour (r g b) = ({} {} {})", path,
                     mi, v, c.r, c.g, c.b);
        mesh.colors_bgr.push_back(ClampedBgr(c));
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
