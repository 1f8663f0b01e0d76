// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// LoadMesh (mesh/mesh_io.h) on one mesh format, for the mesh_<format>_fuzzer targets. The
// input is a bundle (fuzz_support.h): the mesh file m.<extension>, then any files beside it
// (an OBJ's MTL, a glTF's buffers, m_projectors.json, ...). An image t.png is always there
// for textures to name. Errors name one of the files. A mesh LoadMesh returns passes
// Mesh::Check and has unit normals, finite uvs and colours in [0, 1].
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace unseen::fuzz {

// `extension` without the dot. For "gltf", a file that starts with the binary magic "glTF"
// is named m.glb.
int FuzzLoadMesh(const uint8_t* data, size_t size, const std::string& extension);

}  // namespace unseen::fuzz
