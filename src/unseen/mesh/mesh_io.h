// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Reading and writing meshes. Loading goes through assimp (OBJ+MTL, PLY with vertex
// colours or texture, glTF 2, Collada, ...); textures are read from beside the file.
#pragma once

#include <string>

#include "unseen/mesh/mesh.h"

namespace unseen {

// Loads a mesh and multiplies positions by `scale_to_metres` (0.001 for BOP models in
// millimetres). Merges all sub-meshes into one Mesh. Throws unseen::Error naming the file
// for a missing/unreadable file, no triangles, NaN vertices, or a missing texture file.
//
// Details: polygons are triangulated, node transforms applied, vertices with identical
// attributes shared; one Material per material the triangles use, textures (file or
// embedded) loaded with their uvs in the OBJ convention (glTF's are converted); vertex
// colours kept. The object frame is the file's coordinates (no up-axis rotation), except
// that a Collada <unit> is applied by assimp. A BOP-style PLY's `comment TextureFile`
// textures its per-vertex texture_u/texture_v (or s/t), or MeshLab-style per-face
// `texcoord` lists (one texture only). `<stem>_projectors.json` beside
// the file (see SaveMesh) is read into Mesh::projectors.
Mesh LoadMesh(const std::string& path, double scale_to_metres = 1.0);

// Saves `mesh` as PLY (binary, vertex colours or uv + texture comment) or OBJ+MTL (+ PNG
// textures beside it), by extension, with positions multiplied by `scale_from_metres`
// (1000 for BOP). A mesh with projective textures also writes `<stem>_projectors.json`
// and the projector images beside it, which LoadMesh reads back.
//
// Details: a PLY holds one texture, `<stem>.png`; several textured materials are packed
// into it as an atlas (their uvs must then lie in [0, 1]; repeating uvs need .obj), and
// untextured materials of a PLY without texture or vertex colours become vertex colours.
// An OBJ writes `<stem>.mtl` and `<stem>_<material>.png`, vertex colours as
// "v x y z r g b". The projector file holds per projector the image file name, the
// intrinsics (width, height, fx, fy, cx, cy, distortion) and cam_from_obj (row-major
// rotation, translation in file units); saving without projectors removes a stale one.
// Missing folders are created. Throws unseen::Error naming the file for an invalid mesh,
// another extension, or a write failure.
void SaveMesh(const Mesh& mesh, const std::string& path, double scale_from_metres = 1.0);

}  // namespace unseen
