// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Mesh reading, glTF 2 and Collada: embedded and external textures, vertex and material
// colours, node transforms and units, and the malformed files that would crash assimp.
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <cstring>
#include <filesystem>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "unseen/mesh/mesh_io.h"
#include "unseen/mesh/test_mesh_files.h"

namespace unseen {
namespace {

using testing::ExpectSameAppearance;
using testing::ExpectThrowsMentioning;
using testing::IsBlue;
using testing::IsRed;
using testing::kQuadObj;
using testing::MeshIoTest;
using testing::SampleUv;
using testing::TopRedBottomBlue;

// ---------------------------------------------------------------------------------------
// glTF 2 and Collada

std::string Base64(const std::vector<unsigned char>& bytes) {
  static const char* kTable = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned n = (bytes[i] << 16) | (bytes[i + 1] << 8) | bytes[i + 2];
    for (int k = 3; k >= 0; --k) out.push_back(kTable[(n >> (6 * k)) & 63]);
  }
  if (i + 1 == bytes.size()) {
    const unsigned n = bytes[i] << 16;
    out += {kTable[(n >> 18) & 63], kTable[(n >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const unsigned n = (bytes[i] << 16) | (bytes[i + 1] << 8);
    out += {kTable[(n >> 18) & 63], kTable[(n >> 12) & 63], kTable[(n >> 6) & 63], '='};
  }
  return out;
}

template <typename T>
void Append(std::vector<unsigned char>* bytes, const std::vector<T>& values) {
  const auto* p = reinterpret_cast<const unsigned char*>(values.data());
  bytes->insert(bytes->end(), p, p + values.size() * sizeof(T));
}

// A textured unit quad (z = 0, facing +z) in glTF 2 with every buffer and the PNG
// embedded as data URIs, under a node translated by (5, 0, 0). glTF texture coordinates
// have (0, 0) at the top-left of the image: the top of the quad gets v = 0.
std::string QuadGltf(const std::string& image_uri) {
  const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const std::vector<float> uvs = {0, 1, 1, 1, 1, 0, 0, 0};
  const std::vector<uint16_t> indices = {0, 1, 2, 0, 2, 3};
  std::vector<unsigned char> buffer;
  Append(&buffer, positions);  // 48 bytes
  Append(&buffer, uvs);        // 32 bytes
  Append(&buffer, indices);    // 12 bytes
  return R"({"asset": {"version": "2.0"},
  "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0, "translation": [5, 0, 0]}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2,
                              "material": 0}]}],
  "materials": [{"name": "painted", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
  "textures": [{"source": 0}],
  "images": [{"uri": ")" +
         image_uri + R"("}],
  "buffers": [{"byteLength": 92, "uri": "data:application/octet-stream;base64,)" +
         Base64(buffer) + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                  {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                  {"buffer": 0, "byteOffset": 80, "byteLength": 12}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
     "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
    {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}]
})";
}

void ExpectQuadTopRed(const Mesh& mesh, float x_offset) {
  ASSERT_EQ(mesh.num_triangles(), 2);
  ASSERT_TRUE(mesh.HasUvTexture());
  Eigen::Vector3f lo, hi;
  mesh.BoundingBox(&lo, &hi);
  EXPECT_TRUE(lo.isApprox(Eigen::Vector3f(x_offset, 0, 0))) << lo.transpose();
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.triangles[t][k];
      const cv::Vec3f c = SampleUv(mesh.materials[mesh.triangle_materials[t]].texture, mesh.uvs[v]);
      EXPECT_TRUE(mesh.vertices[v].y() > 0.5f ? IsRed(c) : IsBlue(c)) << mesh.vertices[v] << c;
    }
  }
}

TEST_F(MeshIoTest, GltfEmbeddedTextureAndNodeTransform) {
  std::vector<unsigned char> png;
  cv::imencode(".png", TopRedBottomBlue(), png);
  const Mesh mesh = LoadMesh(Write("quad.gltf", QuadGltf("data:image/png;base64," + Base64(png))));
  ExpectQuadTopRed(mesh, 5.0f);
  EXPECT_EQ(mesh.materials[0].name, "painted");
  EXPECT_EQ(mesh.materials[0].texture_path, "");  // embedded: no file of its own
}

TEST_F(MeshIoTest, GltfImageMediaTypeWithoutSubtypeIsAnError) {
  std::vector<unsigned char> png;
  cv::imencode(".png", TopRedBottomBlue(), png);
  const std::string path = Write("quad.gltf", QuadGltf("data:imagepng;base64," + Base64(png)));
  ExpectThrowsMentioning([&] { LoadMesh(path); }, {path, "imagepng"});
}

TEST_F(MeshIoTest, AGltfFileNeitherGltfReaderRecognisesIsAnError) {
  // Not JSON: without the check assimp guessed the format from the content and read it
  // with another importer (here OpenGEX, for the keyword IndexArray).
  const std::string path = Write("guess.gltf", "g IndexArray {float {1, 2}} Metric {}\n");
  ExpectThrowsMentioning([&] { LoadMesh(path); }, {path, "format"});
}

TEST_F(MeshIoTest, GltfExternalTexture) {
  cv::imwrite(Path("quad texture.png"), TopRedBottomBlue());
  const Mesh mesh = LoadMesh(Write("quad.gltf", QuadGltf("quad%20texture.png")));
  ExpectQuadTopRed(mesh, 5.0f);
  std::filesystem::remove(Path("quad texture.png"));
  ExpectThrowsMentioning([&] { LoadMesh(Path("quad.gltf")); }, {"quad.gltf", "quad%20texture.png"});
}

// A triangle with per-vertex colours (COLOR_0) and a material with a base colour factor.
std::string ColouredTriangleGltf(
    const std::vector<float>& colours = {1, 0, 0, 0, 1, 0, 0, 0, 1}) {  // RGB per vertex
  const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::vector<unsigned char> buffer;
  Append(&buffer, positions);
  Append(&buffer, colours);
  return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "COLOR_0": 1}, "material": 0}]}],
  "materials": [{"name": "tinted", "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 1]}}],
  "buffers": [{"byteLength": 72, "uri": "data:application/octet-stream;base64,)" +
         Base64(buffer) + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                  {"buffer": 0, "byteOffset": 36, "byteLength": 36}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
     "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"}]
})";
}

TEST_F(MeshIoTest, GltfVertexColoursAndBaseColour) {
  const Mesh mesh = LoadMesh(Write("tri.gltf", ColouredTriangleGltf()));
  ASSERT_EQ(mesh.num_triangles(), 1);
  ASSERT_EQ(mesh.materials.size(), 1u);
  EXPECT_TRUE(mesh.materials[0].diffuse_bgr.isApprox(Eigen::Vector3f(0.6f, 0.4f, 0.2f), 1e-5f))
      << mesh.materials[0].diffuse_bgr.transpose();
  ASSERT_EQ(mesh.colors_bgr.size(), 3u);
  for (int v = 0; v < 3; ++v) {
    const Eigen::Vector3f& p = mesh.vertices[v];
    const Eigen::Vector3f expected = p.x() > 0.5f   ? Eigen::Vector3f(0, 1, 0)
                                     : p.y() > 0.5f ? Eigen::Vector3f(1, 0, 0)
                                                    : Eigen::Vector3f(0, 0, 1);
    EXPECT_TRUE(mesh.colors_bgr[v].isApprox(expected, 1e-5f)) << mesh.colors_bgr[v].transpose();
  }
}

TEST_F(MeshIoTest, AVertexColourThatIsNotANumberIsAnError) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::string path = Write("nan.gltf", ColouredTriangleGltf({1, 0, 0, 0, nan, nan, 0, 0, 1}));
  ExpectThrowsMentioning([&] { LoadMesh(path); }, {path, "vertex 1", "colour"});
}

// Loads `source` with assimp and writes it with assimp's exporter `format_id`.
void AssimpConvert(const std::string& source, const std::string& format_id,
                   const std::string& target) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(source, aiProcess_Triangulate);
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  Assimp::Exporter exporter;
  ASSERT_EQ(exporter.Export(scene, format_id, target), AI_SUCCESS) << exporter.GetErrorString();
}

TEST_F(MeshIoTest, ColladaAndGlbFromAssimpExporter) {
  cv::imwrite(Path("quad.png"), TopRedBottomBlue());
  Write("quad.mtl", "newmtl tex\nKd 1 1 1\nmap_Kd quad.png\n");
  const std::string obj = Write("quad.obj", kQuadObj);
  const Mesh reference = LoadMesh(obj);
  AssimpConvert(obj, "collada", Path("quad.dae"));
  ExpectSameAppearance(reference, LoadMesh(Path("quad.dae")), 1e-3f);
  AssimpConvert(obj, "glb2", Path("quad.glb"));
  ExpectSameAppearance(reference, LoadMesh(Path("quad.glb")), 1e-3f);
  AssimpConvert(obj, "gltf2", Path("quad2.gltf"));
  ExpectSameAppearance(reference, LoadMesh(Path("quad2.gltf")), 1e-3f);
}

TEST_F(MeshIoTest, ColladaKeepsFileAxesAndAppliesUnit) {
  const std::string obj = Write("t.obj", "v 0 0 0\nv 1 0 0\nv 0 2 0\nv 0 0 3\nf 1 2 3\nf 1 4 2\n");
  AssimpConvert(obj, "collada", Path("t.dae"));
  std::ifstream in(Path("t.dae"));
  std::string text((std::istreambuf_iterator<char>(in)), {});
  for (const auto& [from, to] :
       {std::pair<std::string, std::string>{"Y_UP", "Z_UP"},
        std::pair<std::string, std::string>{"meter=\"1\"", "meter=\"0.01\""}}) {
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  }
  const Mesh mesh = LoadMesh(Write("z_up_cm.dae", text));
  Eigen::Vector3f lo, hi;
  mesh.BoundingBox(&lo, &hi);
  EXPECT_TRUE(lo.isApprox(Eigen::Vector3f::Zero()) || lo.norm() < 1e-7f) << lo.transpose();
  EXPECT_TRUE(hi.isApprox(Eigen::Vector3f(0.01f, 0.02f, 0.03f), 1e-5f)) << hi.transpose();
}

TEST_F(MeshIoTest, ColladaDataArrayWithoutValuesIsAnError) {
  const std::string obj = Write("t.obj", "v 0 0 0\nv 1 0 0\nv 0 2 0\nf 1 2 3\n");
  AssimpConvert(obj, "collada", Path("t.dae"));
  std::string text = ReadFile(Path("t.dae"));
  const size_t array = text.find("<float_array");
  ASSERT_NE(array, std::string::npos);
  const size_t count = text.find("count=\"", array);
  ASSERT_NE(count, std::string::npos);
  text.replace(count, text.find('"', count + 7) + 1 - count, "count=\"0\"");
  const std::string path = Write("empty_array.dae", text);
  ExpectThrowsMentioning([&] { LoadMesh(path); }, {path, "count=\"0\""});

  // A stride whose index arithmetic wraps around.
  text = ReadFile(Path("t.dae"));
  const size_t stride = text.find("stride=\"");
  ASSERT_NE(stride, std::string::npos);
  text.replace(stride, text.find('"', stride + 8) + 1 - stride, "stride=\"4294967296\"");
  const std::string huge_stride = Write("huge_stride.dae", text);
  ExpectThrowsMentioning([&] { LoadMesh(huge_stride); }, {huge_stride, "stride"});
}

TEST_F(MeshIoTest, ColladaPolylistWithoutPolygonSizesIsAnError) {
  // A quad as a <polylist>; without its <vcount> assimp dereferences a null pointer.
  const std::string quad = R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <library_geometries><geometry id="quad"><mesh>
    <source id="pos"><float_array id="pos-array" count="12">0 0 0 1 0 0 1 1 0 0 1 0</float_array>
      <technique_common><accessor source="#pos-array" count="4" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="vtx"><input semantic="POSITION" source="#pos"/></vertices>
    <polylist count="1"><input semantic="VERTEX" source="#vtx" offset="0"/>
      SIZES<p>0 1 2 3</p></polylist>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="scene"><node id="n">
    <instance_geometry url="#quad"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)";
  std::string with = quad;
  with.replace(with.find("SIZES"), 5, "<vcount>4</vcount>");
  EXPECT_EQ(LoadMesh(Write("quad.dae", with)).num_triangles(), 2);
  std::string without = quad;
  without.replace(without.find("SIZES"), 5, "");
  const std::string path = Write("no_vcount.dae", without);
  ExpectThrowsMentioning([&] { LoadMesh(path); }, {path, "<vcount>"});
}

}  // namespace
}  // namespace unseen
