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
Mesh LoadMesh(const std::string& path, double scale_to_metres = 1.0);

// Saves `mesh` as PLY (binary, vertex colours or uv + texture comment) or OBJ+MTL (+ PNG
// textures beside it), by extension, with positions multiplied by `scale_from_metres`
// (1000 for BOP). A mesh with projective textures also writes `<stem>_projectors.json`
// and the projector images beside it, which LoadMesh reads back.
void SaveMesh(const Mesh& mesh, const std::string& path, double scale_from_metres = 1.0);

}  // namespace unseen
