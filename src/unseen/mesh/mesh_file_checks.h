// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Checks of mesh files made before assimp 5.2 reads them, for the malformed input it does not
// survive (found by fuzzing: endless loops, null dereferences, gigabyte allocations), and
// the PLY body reader that also recovers per-face texture coordinates. Internal to the mesh
// module (LoadMesh); each check throws unseen::Error naming the file and the line or field.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

struct aiScene;
namespace Assimp {
class Importer;
}  // namespace Assimp

namespace unseen::mesh_checks {

// `s` without leading and trailing blanks.
std::string Trim(const std::string& s);

// The whole file as text.
std::string ReadText(const std::string& path);

// PLY header against the PLY grammar.
void CheckPlyHeader(const std::string& path);

// OBJ: face, line and point indices against the file's vertex, uv and normal counts; and
// the material libraries it may make assimp read (its mtllib files and <stem>.mtl), where
// every statement of a material must follow a newmtl line.
void CheckObjFile(const std::string& path);

// Collada index lists and data-array counts.
void CheckColladaText(const std::string& path);

// glTF JSON nesting and .glb header lengths.
void CheckGltfText(const std::string& path, bool binary);

// assimp picks the importer by the file's extension; when several claim it (.gltf: glTF 1
// and 2) and every one of them turns the file down, it guesses the format from the content
// among all its importers, whose bugs a malformed .gltf was found to reach (read as
// OpenGEX: a heap overflow). Throws naming the file unless one importer claims the
// extension, or one of those that claim it recognises the file.
void CheckImporterForExtension(const Assimp::Importer& importer, const std::string& path);

// Faces without indices, indices out of range and non-finite positions in assimp's raw scene.
void CheckRawScene(const aiScene& scene, const std::string& path);

// Per-face texture coordinates of a PLY (MeshLab style: a face list property `texcoord`
// with u, v per corner). assimp stores them per vertex, keeping one corner's value where
// faces disagree, which garbles textures along seams; they are read here instead.
struct PlyFaceTexcoords {
  std::vector<std::vector<int64_t>> indices;   // per face, vertex indices as in the file
  std::vector<std::vector<double>> texcoords;  // per face, u0 v0 u1 v1 ...
  bool several_textures = false;               // a `texnumber` other than 0 was seen
};

// Reads the body of a PLY before assimp does: checks that every list has at most 1e6
// entries (assimp allocates what an ASCII list count says) and returns the face texcoords,
// or std::nullopt when the faces have none.
std::optional<PlyFaceTexcoords> ReadPlyBody(const std::string& path);

// Gives every face corner of assimp's raw PLY mesh its own vertex carrying the face's
// texture coordinates (positions, normals and colours copied).
void ApplyPlyFaceTexcoords(const PlyFaceTexcoords& faces, const std::string& path,
                           aiScene* scene);

}  // namespace unseen::mesh_checks
