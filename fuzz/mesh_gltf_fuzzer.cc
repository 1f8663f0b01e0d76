// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// LoadMesh on .gltf and .glb files (see fuzz_mesh.h).
#include "fuzz/fuzz_mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return unseen::fuzz::FuzzLoadMesh(data, size, "gltf");
}
