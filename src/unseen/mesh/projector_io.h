// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The projector file beside a mesh file (mesh_io.h): `<stem>_projectors.json` holds per
// projective texture the image file name, the pinhole intrinsics and cam_from_obj (rotation
// row-major, translation in the mesh file's units); the images are PNGs beside it.
#pragma once

#include <filesystem>
#include <vector>

#include "unseen/mesh/mesh.h"

namespace unseen {

// `<dir>/<stem>_projectors.json` for a mesh file `<dir>/<stem>.<ext>`.
std::filesystem::path ProjectorsPath(const std::filesystem::path& mesh_path);

// The projectors of a projector file (translations in the file's units, as written).
// Throws unseen::Error naming the file, the projector and the field for malformed JSON, a
// missing or unreadable image, an image whose size is not the camera's, a non-rotation.
std::vector<Projector> ReadProjectors(const std::filesystem::path& json_path);

// Writes mesh.projectors (translations times `scale`) and their images beside
// `mesh_path`; without projectors, removes a stale projector file.
void SaveProjectors(const Mesh& mesh, const std::filesystem::path& mesh_path, float scale);

}  // namespace unseen
