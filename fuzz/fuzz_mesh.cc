// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "fuzz/fuzz_mesh.h"

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "fuzz/fuzz_support.h"
#include "unseen/mesh/mesh_io.h"

// Leaks inside assimp are not unseen's to fix (assimp 5.2's importers drop what they built
// when they throw on some malformed files); LeakSanitizer ignores them in the mesh targets.
extern "C" const char* __lsan_default_suppressions() { return "leak:libassimp.so\n"; }

namespace unseen::fuzz {

namespace {

void CheckMesh(const Mesh& mesh) {
  try {
    mesh.Check();
  } catch (const Error& e) {
    Fail(std::string("LoadMesh returned a mesh that fails its check: ") + e.what());
  }
  for (size_t v = 0; v < mesh.normals.size(); ++v) {
    UNSEEN_FUZZ_EXPECT(mesh.normals[v].allFinite() && std::abs(mesh.normals[v].norm() - 1) < 1e-3,
                       "normal {} = ({} {} {})", v, mesh.normals[v].x(), mesh.normals[v].y(),
                       mesh.normals[v].z());
  }
  for (size_t v = 0; v < mesh.uvs.size(); ++v) {
    UNSEEN_FUZZ_EXPECT(mesh.uvs[v].allFinite(), "uv {} = ({} {})", v, mesh.uvs[v].x(),
                       mesh.uvs[v].y());
  }
  for (size_t v = 0; v < mesh.colors_bgr.size(); ++v) {
    const Eigen::Vector3f& c = mesh.colors_bgr[v];
    UNSEEN_FUZZ_EXPECT(c.allFinite() && c.minCoeff() >= 0 && c.maxCoeff() <= 1,
                       "colour {} = ({} {} {})", v, c.x(), c.y(), c.z());
  }
  for (const Material& m : mesh.materials) {
    const Eigen::Vector3f& c = m.diffuse_bgr;
    UNSEEN_FUZZ_EXPECT(c.allFinite() && c.minCoeff() >= 0 && c.maxCoeff() <= 1,
                       "material '{}' colour ({} {} {})", m.name, c.x(), c.y(), c.z());
  }
}

}  // namespace

int FuzzLoadMesh(const uint8_t* data, size_t size, const std::string& extension) {
  Init();
  static const Scratch scratch("mesh_" + extension);
  static const std::vector<uchar> texture = [] {
    std::vector<uchar> png;
    cv::imencode(".png", cv::Mat(4, 8, CV_8UC3, cv::Scalar(40, 90, 200)), png);
    return png;
  }();
  const std::string_view input = AsText(data, size);
  std::string name = "m." + extension;
  if (extension == "gltf" && input.substr(0, 4) == "glTF") name = "m.glb";
  const auto files = SplitBundle(input, name);
  if (!files) return 0;
  scratch.Reset();
  scratch.Write("t.png",
                std::string_view(reinterpret_cast<const char*>(texture.data()), texture.size()));
  if (!scratch.WriteBundle(*files)) return 0;
  const std::string path = (scratch.dir() / name).string();
  // Errors name the mesh or the file beside it that is wrong (a texture, projectors).
  ExpectReaderContract("LoadMesh", scratch.dir().string(), [&] { CheckMesh(LoadMesh(path)); });
  return 0;
}

}  // namespace unseen::fuzz
