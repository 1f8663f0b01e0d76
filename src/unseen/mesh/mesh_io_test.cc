// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "unseen/mesh/mesh_io.h"

#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "unseen/image/image_io.h"
#include "unseen/mesh/primitives.h"
#include "unseen/mesh/test_mesh_files.h"
#include "unseen/util/error.h"

namespace unseen {
namespace {

namespace fs = std::filesystem;

const std::string kSequences = std::string(UNSEEN_SOURCE_DIR) + "/../shared/data/sequences";

using testing::ExpectOutward;
using testing::ExpectSameAppearance;
using testing::ExpectTexturesNotMirrored;
using testing::ExpectThrowsMentioning;
using testing::IsBlue;
using testing::IsRed;
using testing::kQuadObj;
using testing::MeshIoTest;
using testing::SampleUv;
using testing::SurfaceColour;
using testing::TopRedBottomBlue;

// ---------------------------------------------------------------------------------------
// Development sequence models (Blender OBJ exports, millimetres).

std::string DevModel(const std::string& sequence) {
  return kSequences + "/" + sequence + "/models/obj_000001.obj";
}

TEST(DevModels, CubesLoadInMetres) {
  int loaded = 0;
  for (const char* sequence : {"cube_white_zigzag", "cube_clutter_sidelight", "rig5_cube_fig312"}) {
    const std::string path = DevModel(sequence);
    if (!fs::exists(path)) continue;
    ++loaded;
    const Mesh cube = LoadMesh(path, 0.001);
    EXPECT_EQ(cube.num_triangles(), 12) << path;
    Eigen::Vector3f lo, hi;
    cube.BoundingBox(&lo, &hi);
    EXPECT_LT((lo - Eigen::Vector3f::Constant(-0.048f)).norm(), 1e-6f) << path;
    EXPECT_LT((hi - Eigen::Vector3f::Constant(0.048f)).norm(), 1e-6f) << path;
    ASSERT_EQ(cube.materials.size(), 6u) << path;
    for (const Material& m : cube.materials) {
      EXPECT_FALSE(m.texture.empty()) << m.name;
      EXPECT_EQ(m.texture.type(), CV_32FC3);
      EXPECT_EQ(m.texture.size(), cv::Size(256, 256));
      // The texture is the file as it is (not flipped): compare with a direct load.
      const cv::Mat direct =
          LoadColorImage(kSequences + "/" + sequence + "/models/" + m.texture_path);
      EXPECT_EQ(cv::norm(direct, m.texture, cv::NORM_INF), 0.0) << m.texture_path;
    }
    ASSERT_EQ(cube.uvs.size(), cube.vertices.size());
    for (const Eigen::Vector2f& uv : cube.uvs) {
      EXPECT_TRUE((uv.array() >= 0.0f).all() && (uv.array() <= 1.0f).all());
    }
    EXPECT_TRUE(cube.HasUvTexture());
    ExpectOutward(cube);
    ExpectTexturesNotMirrored(cube);
    Eigen::Vector3f centre;
    float radius;
    cube.BoundingSphere(&centre, &radius);
    EXPECT_NEAR(radius, 0.048f * std::sqrt(3.0f), 1e-5f);
  }
  if (loaded == 0) GTEST_SKIP() << "development sequences not found in " << kSequences;
}

TEST(DevModels, SphereAndBox) {
  const std::string sphere_path = DevModel("sphere_clutter_spin");
  const std::string box_path = DevModel("box_occluded_bar");
  if (!fs::exists(sphere_path) && !fs::exists(box_path)) GTEST_SKIP() << "no dev sequences";
  if (fs::exists(sphere_path)) {
    const Mesh sphere = LoadMesh(sphere_path, 0.001);
    Eigen::Vector3f centre;
    float radius;
    sphere.BoundingSphere(&centre, &radius);
    EXPECT_LT(centre.norm(), 1e-3f);
    EXPECT_NEAR(radius, 0.060f, 1e-3f);  // models_info.json: diameter 120 mm
    EXPECT_GT(sphere.num_triangles(), 500);
    EXPECT_TRUE(sphere.HasUvTexture());
    ExpectOutward(sphere);
  }
  if (fs::exists(box_path)) {
    const Mesh box = LoadMesh(box_path, 0.001);
    EXPECT_EQ(box.num_triangles(), 12);
    Eigen::Vector3f lo, hi;
    box.BoundingBox(&lo, &hi);
    EXPECT_LT((hi - Eigen::Vector3f(0.08f, 0.05f, 0.03f)).norm(), 1e-6f);
    EXPECT_LT((lo + Eigen::Vector3f(0.08f, 0.05f, 0.03f)).norm(), 1e-6f);
    EXPECT_EQ(box.materials.size(), 6u);
    EXPECT_TRUE(box.HasUvTexture());
    ExpectOutward(box);
    ExpectTexturesNotMirrored(box);
  }
}

// ---------------------------------------------------------------------------------------
// OBJ

TEST_F(MeshIoTest, ObjTextureIsRightWayUp) {
  cv::imwrite(Path("quad.png"), TopRedBottomBlue());
  Write("quad.mtl", "newmtl tex\nKd 1 1 1\nmap_Kd quad.png\n");
  const Mesh mesh = LoadMesh(Write("quad.obj", kQuadObj));
  ASSERT_EQ(mesh.num_triangles(), 2);
  ASSERT_EQ(mesh.materials.size(), 1u);
  EXPECT_EQ(mesh.materials[0].name, "tex");
  EXPECT_EQ(mesh.materials[0].texture_path, "quad.png");
  ASSERT_TRUE(mesh.HasUvTexture());
  // The top of the quad (y = 1) shows the top of the image (red), the bottom blue.
  for (int t = 0; t < 2; ++t) {
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.triangles[t][k];
      const cv::Vec3f c = SampleUv(mesh.materials[0].texture, mesh.uvs[v]);
      if (mesh.vertices[v].y() > 0.5f) {
        EXPECT_TRUE(IsRed(c)) << c;
      } else {
        EXPECT_TRUE(IsBlue(c)) << c;
      }
    }
  }
  // Counter-clockwise seen from +z is kept.
  const Eigen::Vector3i& tri = mesh.triangles[0];
  const Eigen::Vector3f n = (mesh.vertices[tri[1]] - mesh.vertices[tri[0]])
                                .cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]]);
  EXPECT_GT(n.z(), 0.0f);
}

TEST_F(MeshIoTest, ObjDiffuseColoursMergeSubMeshesAndScale) {
  Write("two.mtl", "newmtl red\nKd 1 0 0\nnewmtl green\nKd 0 1 0\nnewmtl unused\nKd 0 0 1\n");
  const Mesh mesh = LoadMesh(Write("two.obj", R"(mtllib two.mtl
o first
v 0 0 0
v 10 0 0
v 0 10 0
v 0 0 10
usemtl red
f 1 2 3
o second
usemtl green
f 1 3 4
f 1 4 2
)"),
                             0.001);
  EXPECT_EQ(mesh.num_triangles(), 3);
  ASSERT_EQ(mesh.materials.size(), 2u);  // only the used ones
  Eigen::Vector3f lo, hi;
  mesh.BoundingBox(&lo, &hi);
  EXPECT_TRUE(hi.isApprox(Eigen::Vector3f(0.01f, 0.01f, 0.01f)));
  int red = 0, green = 0;
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    const Eigen::Vector3f& d = mesh.materials[mesh.triangle_materials[t]].diffuse_bgr;
    red += d.isApprox(Eigen::Vector3f(0, 0, 1));
    green += d.isApprox(Eigen::Vector3f(0, 1, 0));
  }
  EXPECT_EQ(red, 1);
  EXPECT_EQ(green, 2);
  EXPECT_FALSE(mesh.HasUvTexture());
}

TEST_F(MeshIoTest, ObjQuadsAreTriangulated) {
  const Mesh mesh = LoadMesh(Write("q.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"));
  EXPECT_EQ(mesh.num_triangles(), 2);
  EXPECT_NO_THROW(mesh.Check());
}

TEST_F(MeshIoTest, NormalsAreUnitOrDropped) {
  const Mesh scaled =
      LoadMesh(Write("n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 2\nf 1//1 2//1 3//1\n"));
  ASSERT_EQ(scaled.normals.size(), 3u);
  for (const Eigen::Vector3f& n : scaled.normals) EXPECT_TRUE(n.isApprox(Eigen::Vector3f(0, 0, 1)));
  const Mesh zero =
      LoadMesh(Write("z.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nf 1//1 2//1 3//1\n"));
  EXPECT_TRUE(zero.normals.empty());
}

TEST_F(MeshIoTest, ObjMissingTextureNamesBothFiles) {
  Write("quad.mtl", "newmtl tex\nKd 1 1 1\nmap_Kd no_such_texture.png\n");
  const std::string path = Write("quad.obj", kQuadObj);
  ExpectThrowsMentioning([&] { LoadMesh(path); }, {path, "no_such_texture.png"});
}

TEST_F(MeshIoTest, ObjMaterialStatementBeforeNewmtlIsRefused) {
  // assimp 5.2 crashes on a material statement outside any material; it also reads
  // <stem>.mtl when the named library is missing.
  Write("quad.mtl", "# comment\n\nmap_Kd quad.png\nnewmtl tex\n");
  const std::string path = Write("quad.obj", kQuadObj);
  ExpectThrowsMentioning([&] { LoadMesh(path); }, {"quad.mtl", "line 3", "newmtl"});
  Write("fallback.mtl", "Kd 1 0 0\n");
  const std::string fallback = Write("fallback.obj", "mtllib missing.mtl\nv 0 0 0\n");
  ExpectThrowsMentioning([&] { LoadMesh(fallback); }, {"fallback.mtl", "line 1"});
}

// ---------------------------------------------------------------------------------------
// PLY

TEST_F(MeshIoTest, PlyVertexColours) {
  const Mesh mesh = LoadMesh(Write("tet.ply", R"(ply
format ascii 1.0
element vertex 4
property float x
property float y
property float z
property uchar red
property uchar green
property uchar blue
element face 4
property list uchar int vertex_indices
end_header
0 0 0 255 0 0
1 0 0 0 255 0
0 1 0 0 0 255
0 0 1 255 255 255
3 0 2 1
3 0 1 3
3 0 3 2
3 1 2 3
)"));
  EXPECT_EQ(mesh.num_triangles(), 4);
  ASSERT_EQ(mesh.colors_bgr.size(), mesh.vertices.size());
  EXPECT_FALSE(mesh.HasUvTexture());
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3f& p = mesh.vertices[v];
    Eigen::Vector3f expected(1, 1, 1);
    if (p.isApprox(Eigen::Vector3f(0, 0, 0))) expected = {0, 0, 1};  // red, BGR
    if (p.isApprox(Eigen::Vector3f(1, 0, 0))) expected = {0, 1, 0};
    if (p.isApprox(Eigen::Vector3f(0, 1, 0))) expected = {1, 0, 0};
    EXPECT_TRUE(mesh.colors_bgr[v].isApprox(expected, 1e-3f))
        << p.transpose() << ": " << mesh.colors_bgr[v].transpose();
  }
  // Tetrahedron with outward winding in the file stays outward.
  const Eigen::Vector3f inside(0.2f, 0.2f, 0.2f);
  for (const Eigen::Vector3i& tri : mesh.triangles) {
    const Eigen::Vector3f& a = mesh.vertices[tri[0]];
    const Eigen::Vector3f n = (mesh.vertices[tri[1]] - a).cross(mesh.vertices[tri[2]] - a);
    EXPECT_GT(n.dot(a - inside), 0.0f);
  }
}

std::string TexturedPlyText(const std::string& u_name, const std::string& v_name,
                            const std::string& texture) {
  return "ply\nformat ascii 1.0\ncomment TextureFile " + texture + "  " +
         "\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
         "property float " +
         u_name + "\nproperty float " + v_name +
         "\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n3 0 1 2\n3 0 2 3\n";
}

TEST_F(MeshIoTest, PlyTextureFileComment) {
  cv::imwrite(Path("tex.png"), TopRedBottomBlue());
  for (const auto& [u, v] : {std::pair{"texture_u", "texture_v"}, std::pair{"s", "t"}}) {
    const Mesh mesh =
        LoadMesh(Write(std::string("bop_") + u + ".ply", TexturedPlyText(u, v, "tex.png")));
    ASSERT_TRUE(mesh.HasUvTexture()) << u;
    EXPECT_EQ(mesh.materials[0].texture_path, "tex.png");
    for (int t = 0; t < mesh.num_triangles(); ++t) {
      const cv::Vec3f c = SurfaceColour(mesh, t, {0.34f, 0.33f, 0.33f});
      const float y = (mesh.vertices[mesh.triangles[t][0]] + mesh.vertices[mesh.triangles[t][1]] +
                       mesh.vertices[mesh.triangles[t][2]])
                          .y() /
                      3.0f;
      EXPECT_TRUE(y > 0.5f ? IsRed(c) : IsBlue(c)) << u << " triangle " << t << " " << c;
    }
  }
}

// Appends `value` to `bytes` in little- or big-endian order.
template <typename T>
void PutBinary(T value, bool big_endian, std::string* bytes) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if (big_endian) std::reverse(raw, raw + sizeof(T));
  bytes->append(raw, sizeof(T));
}

// A unit quad whose two triangles take their uvs per face (MeshLab's `texcoord` list): the
// first maps to the left half of the texture, the second to the right half, and the shared
// vertices 0 and 2 have different uvs in the two faces.
std::string SeamPly(const std::string& format) {
  const float positions[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const int faces[2][3] = {{0, 1, 2}, {0, 2, 3}};
  const float uvs[2][6] = {{0, 0, 0.5f, 0, 0.5f, 1}, {0.5f, 0, 1, 1, 0.5f, 1}};
  std::string text = "ply\nformat " + format +
                     " 1.0\ncomment TextureFile halves.png\nelement vertex 4\n"
                     "property float x\nproperty float y\nproperty float z\nelement face 2\n"
                     "property list uchar int vertex_indices\nproperty list uchar float texcoord\n"
                     "property int texnumber\nend_header\n";
  const bool big = format == "binary_big_endian";
  for (const auto& p : positions) {
    if (format == "ascii") {
      text += fmt::format("{} {} {}\n", p[0], p[1], p[2]);
    } else {
      for (float x : p) PutBinary(x, big, &text);
    }
  }
  for (int f = 0; f < 2; ++f) {
    if (format == "ascii") {
      text += fmt::format("3 {} {} {} 6 {} 0\n", faces[f][0], faces[f][1], faces[f][2],
                          fmt::join(uvs[f], " "));
    } else {
      PutBinary<uint8_t>(3, big, &text);
      for (int i : faces[f]) PutBinary<int32_t>(i, big, &text);
      PutBinary<uint8_t>(6, big, &text);
      for (float x : uvs[f]) PutBinary(x, big, &text);
      PutBinary<int32_t>(0, big, &text);
    }
  }
  return text;
}

TEST_F(MeshIoTest, PlyPerFaceTexcoordsKeepSeams) {
  cv::Mat halves(8, 8, CV_8UC3, cv::Scalar(255, 0, 0));  // blue
  halves.colRange(0, 4).setTo(cv::Scalar(0, 0, 255));    // left half red
  cv::imwrite(Path("halves.png"), halves);
  for (const std::string format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    SCOPED_TRACE(format);
    const Mesh mesh = LoadMesh(Write(format + ".ply", SeamPly(format)));
    ASSERT_EQ(mesh.num_triangles(), 2);
    ASSERT_TRUE(mesh.HasUvTexture());
    for (int t = 0; t < 2; ++t) {
      // The face holding vertex (1, 0, 0) is the first one: left half, red.
      bool first = false;
      for (int k = 0; k < 3; ++k) {
        first = first || mesh.vertices[mesh.triangles[t][k]].isApprox(Eigen::Vector3f(1, 0, 0));
      }
      const cv::Vec3f c = SurfaceColour(mesh, t, {1 / 3.f, 1 / 3.f, 1 / 3.f});
      EXPECT_TRUE(first ? IsRed(c) : IsBlue(c)) << "triangle " << t << " " << c;
    }
  }
  // A face whose texcoord list does not have u, v per corner.
  std::string bad = SeamPly("ascii");
  bad.replace(bad.find("6 0.5 0 1 1 0.5 1"), 17, "4 0.5 0 1 1");
  const std::string bad_path = Write("bad_texcoords.ply", bad);
  ExpectThrowsMentioning([&] { LoadMesh(bad_path); }, {bad_path, "texcoord"});
  // Several textures per PLY are refused rather than shown wrongly.
  std::string several = SeamPly("ascii");
  several.replace(several.rfind(" 0\n"), 3, " 1\n");
  const std::string several_path = Write("several.ply", several);
  ExpectThrowsMentioning([&] { LoadMesh(several_path); }, {several_path, "several textures"});
}

TEST_F(MeshIoTest, PlyMissingTextureNamesBothFiles) {
  const std::string path = Write("m.ply", TexturedPlyText("texture_u", "texture_v", "gone.png"));
  ExpectThrowsMentioning([&] { LoadMesh(path); }, {path, "gone.png"});
}

const char* kPlyHeader3 = R"(ply
format ascii 1.0
element vertex 3
property float x
property float y
property float z
)";
// kPlyHeader3 with one triangle's face list, up to the body.
const std::string kPlyTriangleHeader =
    std::string(kPlyHeader3) +
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n";

TEST_F(MeshIoTest, BadInputThrowsNamingTheFile) {
  const std::string missing = Path("does_not_exist.obj");
  ExpectThrowsMentioning([&] { LoadMesh(missing); }, {missing, "not found"});

  const std::string garbage = Write("garbage.ply", "this is not a mesh\n\x01\x02\x03");
  ExpectThrowsMentioning([&] { LoadMesh(garbage); }, {garbage});
  const std::string garbage_obj = Write("garbage.obj", std::string(1000, '\x07'));
  ExpectThrowsMentioning([&] { LoadMesh(garbage_obj); }, {garbage_obj});

  const std::string out_of_range =
      Write("range.ply", kPlyTriangleHeader + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
  ExpectThrowsMentioning([&] { LoadMesh(out_of_range); }, {out_of_range});

  const std::string nan_vertex =
      Write("nan.ply", kPlyTriangleHeader + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n");
  ExpectThrowsMentioning([&] { LoadMesh(nan_vertex); }, {nan_vertex});

  const std::string no_faces =
      Write("nofaces.ply", std::string(kPlyHeader3) + "end_header\n0 0 0\n1 0 0\n0 1 0\n");
  ExpectThrowsMentioning([&] { LoadMesh(no_faces); }, {no_faces});
  const std::string obj_no_faces = Write("nofaces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  ExpectThrowsMentioning([&] { LoadMesh(obj_no_faces); }, {obj_no_faces});

  // Face lists without counts (a classic hand-written mistake): faces with no indices.
  const std::string no_counts = Write(
      "nocounts.ply", std::string(kPlyHeader3) +
                          "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
                          "0 0 0\n1 0 0\n0 1 0\n0 1 2\n0 2 1\n");
  ExpectThrowsMentioning([&] { LoadMesh(no_counts); }, {no_counts});

  const std::string empty = Write("empty.obj", "");
  ExpectThrowsMentioning([&] { LoadMesh(empty); }, {empty});

  const std::string good = Write("good.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_NO_THROW(LoadMesh(good));
  EXPECT_THROW(LoadMesh(good, 0.0), Error);
  EXPECT_THROW(LoadMesh(good, std::nan("")), Error);
}

// ASCII PLY elements are one per line: a face list count on a line of its own is read as
// the count it is (and rejected when it does not fit its type), not as a coordinate.
TEST_F(MeshIoTest, AsciiPlyValuesAreReadLineByLine) {
  const std::string face = kPlyTriangleHeader;
  const std::string short_line = Write("short.ply", face + "0 0 0\n1 0\n0\n1 0\n3 0 1 2\n");
  ExpectThrowsMentioning([&] { LoadMesh(short_line); }, {short_line, "1 0"});
  const std::string huge_count =
      Write("huge.ply", face + "0 0 0\n1 0 0\n0 1\n318446744073709551616 0 1 2\n");
  ExpectThrowsMentioning([&] { LoadMesh(huge_count); }, {huge_count});
  const std::string blank_line = Write("blank.ply", face + "0 0 0\n\n1 0 0\n0 1 0\n3 0 1 2\n");
  ExpectThrowsMentioning([&] { LoadMesh(blank_line); }, {blank_line});
  const std::string crlf = Write("crlf.ply", face + "0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2\r\n");
  EXPECT_EQ(LoadMesh(crlf).num_triangles(), 1);
}

// assimp reads a number's integer part as a 64-bit integer and, when that overflows,
// returns 0 without moving on, so the next property (here a list count) is read from the
// same digits. Such a coordinate is an error naming it; one in exponent form is read.
TEST_F(MeshIoTest, AsciiPlyCoordinateBeyond64BitsIsAnError) {
  const std::string header = kPlyTriangleHeader;
  const std::string beyond =
      Write("beyond.ply", header + "0 0 0\n1 0 118446744073709551616\n0 1 0\n3 0 1 2\n");
  ExpectThrowsMentioning([&] { LoadMesh(beyond); }, {beyond, "118446744073709551616"});
  const std::string signed_beyond =
      Write("signed.ply", header + "0 0 0\n1 0 -18446744073709551616.5\n0 1 0\n3 0 1 2\n");
  ExpectThrowsMentioning([&] { LoadMesh(signed_beyond); }, {signed_beyond, "integer part"});
  const std::string largest =
      Write("largest.ply", header + "0 0 0\n1 0 0018446744073709551615\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(LoadMesh(largest).num_triangles(), 1);
  const std::string exponent =
      Write("exponent.ply", header + "0 0 0\n1 0 1.2e20\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(LoadMesh(exponent).num_triangles(), 1);
}

TEST_F(MeshIoTest, AsciiPlyIntegerPropertyWithAFractionIsAnError) {
  // assimp reads an integer property's digits up to the '.': "8446744070739.1e-320616" (0 as
  // a number) was a list of 8e12 entries to it.
  const std::string header = kPlyTriangleHeader;
  const std::string fraction =
      Write("fraction.ply", header + "0 0 0\n1 0 0\n0 1 0\n8446744070739.1e-320616 0 1 2\n");
  ExpectThrowsMentioning([&] { LoadMesh(fraction); }, {fraction, "not an integer"});
  const std::string index = Write("index.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n");
  ExpectThrowsMentioning([&] { LoadMesh(index); }, {index, "1.5"});
  const std::string plain = Write("plain.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 +1 2\n");
  EXPECT_EQ(LoadMesh(plain).num_triangles(), 1);
}

TEST_F(MeshIoTest, AsciiPlyBodyWithAControlCharacterIsAnError) {
  // A NUL ended assimp's reading of the line where this one went on: its lists took their
  // counts from other values (an 8 GB allocation).
  const std::string header = kPlyTriangleHeader;
  std::string body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 ";
  body += '\0';
  body += "4\n";
  const std::string path = Write("nul.ply", header + body);
  ExpectThrowsMentioning([&] { LoadMesh(path); }, {path, "control character"});
  const std::string tabs = Write("tabs.ply", header + "0\t0\t0\n1 0 0\n0 1 0\r\n3 0 1 2\n");
  EXPECT_EQ(LoadMesh(tabs).num_triangles(), 1);
}

TEST_F(MeshIoTest, PlyHeaderLineWithAVerticalTabIsAnError) {
  // assimp splits words at spaces and tabs only: "vertex_indices\v" was another name to it,
  // a face element without indices, and a null dereference.
  const std::string path =
      Write("vt.ply", std::string(kPlyHeader3) +
                          "element face 1\nproperty list uchar int vertex_indices\v\nend_header\n"
                          "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  ExpectThrowsMentioning([&] { LoadMesh(path); }, {path, "header line"});
}

TEST_F(MeshIoTest, ObjRelativeIndexBeyondEveryIntegerIsAnError) {
  // strtoll clamps it to the most negative integer, whose negation overflows.
  const std::string path =
      Write("far.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -99999999999999999999999\n");
  ExpectThrowsMentioning([&] { LoadMesh(path); }, {path, "-99999999999999999999999"});
}

TEST_F(MeshIoTest, NanVertexInObj) {
  const std::string path = Write("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
  ExpectThrowsMentioning([&] { LoadMesh(path); }, {path});
}

// ---------------------------------------------------------------------------------------
// Saving and loading back

TEST_F(MeshIoTest, LetteredCubeRoundTripsThroughPlyAtlasAndObj) {
  const Mesh cube = MakeLetteredCube(0.096, 64);
  for (const char* name : {"cube.ply", "cube.obj"}) {
    SaveMesh(cube, Path(name), 1000.0);
    const Mesh loaded = LoadMesh(Path(name), 0.001);
    SCOPED_TRACE(name);
    EXPECT_TRUE(loaded.HasUvTexture());
    Eigen::Vector3f lo, hi;
    loaded.BoundingBox(&lo, &hi);
    EXPECT_LT((hi - Eigen::Vector3f::Constant(0.048f)).norm(), 1e-6f);
    // 8-bit PNG rounding: colours within 1/255 + interpolation slack.
    ExpectSameAppearance(cube, loaded, 0.02f);
    ASSERT_EQ(loaded.normals.size(), loaded.vertices.size());
  }
  // The PLY holds one texture (an atlas of the six faces) named in its header.
  std::ifstream ply(Path("cube.ply"), std::ios::binary);
  std::string header((std::istreambuf_iterator<char>(ply)), {});
  EXPECT_NE(header.find("comment TextureFile cube.png"), std::string::npos);
  EXPECT_TRUE(fs::exists(Path("cube.png")));
  // The OBJ keeps six materials with their names.
  const Mesh obj = LoadMesh(Path("cube.obj"));
  ASSERT_EQ(obj.materials.size(), 6u);
  EXPECT_EQ(obj.materials[0].name, "face_A");
}

TEST_F(MeshIoTest, SphereRoundTripKeepsRepeatingUvsInPly) {
  Mesh sphere = MakeTexturedSphere(0.03, 6, 12);
  for (Eigen::Vector2f& uv : sphere.uvs) uv.x() *= 2.0f;  // texture repeated twice around
  SaveMesh(sphere, Path("s.ply"));
  const Mesh loaded = LoadMesh(Path("s.ply"));
  ExpectSameAppearance(sphere, loaded, 0.02f);
  // The same uvs cannot be packed into an atlas with other materials.
  sphere.materials.push_back(sphere.materials[0]);
  sphere.triangle_materials[0] = 1;
  ExpectThrowsMentioning([&] { SaveMesh(sphere, Path("t.ply")); }, {"t.ply", "outside [0, 1]"});
  EXPECT_NO_THROW(SaveMesh(sphere, Path("t.obj")));
}

Mesh ColouredTetrahedron() {
  Mesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  mesh.colors_bgr = {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}, {0.2f, 0.4f, 0.6f}};
  return mesh;
}

TEST_F(MeshIoTest, VertexColoursRoundTrip) {
  const Mesh mesh = ColouredTetrahedron();
  for (const char* name : {"tet.ply", "tet.obj"}) {
    SaveMesh(mesh, Path(name), 1000.0);
    const Mesh loaded = LoadMesh(Path(name), 0.001);
    SCOPED_TRACE(name);
    ASSERT_FALSE(loaded.colors_bgr.empty());
    ExpectSameAppearance(mesh, loaded, 0.01f);
  }
}

TEST_F(MeshIoTest, MaterialColoursBecomeVertexColoursInPly) {
  Mesh mesh = ColouredTetrahedron();
  mesh.colors_bgr.clear();
  mesh.materials.resize(2);
  mesh.materials[0].diffuse_bgr = {0, 0, 1};
  mesh.materials[1].diffuse_bgr = {0, 1, 0};
  mesh.triangle_materials = {0, 1, 1, 0};
  SaveMesh(mesh, Path("m.ply"));
  ExpectSameAppearance(mesh, LoadMesh(Path("m.ply")), 0.01f);
  SaveMesh(mesh, Path("m.obj"));
  ExpectSameAppearance(mesh, LoadMesh(Path("m.obj")), 0.01f);
  // A textured material that no triangle uses does not make the PLY textured.
  mesh.materials.push_back(Material());
  mesh.materials[2].texture = cv::Mat(4, 4, CV_32FC3, cv::Scalar(0.5, 0.5, 0.5));
  mesh.uvs.assign(4, Eigen::Vector2f(0.5f, 0.5f));
  SaveMesh(mesh, Path("unused.ply"));
  const Mesh loaded = LoadMesh(Path("unused.ply"));
  EXPECT_FALSE(loaded.HasUvTexture());
  EXPECT_FALSE(fs::exists(Path("unused.png")));
  ExpectSameAppearance(mesh, loaded, 0.01f);
}

TEST_F(MeshIoTest, ProjectorsRoundTrip) {
  Mesh mesh = ColouredTetrahedron();
  for (int i = 0; i < 2; ++i) {
    Projector p;
    p.camera.width = 40 + i;
    p.camera.height = 30;
    p.camera.fx = 50.0 + i;
    p.camera.fy = 51.0;
    p.camera.cx = 19.5;
    p.camera.cy = 14.5 + i;
    if (i == 1) p.camera.distortion = {0.1, -0.01, 0.001, 0.002, 0.0};
    p.cam_from_obj = Rigid3d(
        Eigen::Quaterniond(Eigen::AngleAxisd(0.3 + i, Eigen::Vector3d(1, 2, 3).normalized())),
        Eigen::Vector3d(0.01, -0.02, 0.3 + i));
    p.image = cv::Mat(p.camera.height, p.camera.width, CV_32FC3);
    cv::randu(p.image, 0.0, 1.0);
    if (i == 1) {  // the surface it saw: 0.2-0.5 m, none in the first column
      p.depth = cv::Mat(p.camera.height, p.camera.width, CV_32FC1);
      cv::randu(p.depth, 0.2, 0.5);
      p.depth.col(0).setTo(0.0f);
      p.depth_tolerance_m = 0.004f;
    }
    mesh.projectors.push_back(p);
  }
  for (const char* name : {"proj.ply", "proj.obj"}) {
    SCOPED_TRACE(name);
    SaveMesh(mesh, Path(name), 1000.0);
    EXPECT_TRUE(fs::exists(Path(fs::path(name).stem().string() + "_projectors.json")));
    const Mesh loaded = LoadMesh(Path(name), 0.001);
    ASSERT_EQ(loaded.projectors.size(), 2u);
    for (int i = 0; i < 2; ++i) {
      const Projector& a = mesh.projectors[i];
      const Projector& b = loaded.projectors[i];
      EXPECT_EQ(a.camera.width, b.camera.width);
      EXPECT_EQ(a.camera.height, b.camera.height);
      EXPECT_DOUBLE_EQ(a.camera.fx, b.camera.fx);
      EXPECT_DOUBLE_EQ(a.camera.cy, b.camera.cy);
      EXPECT_EQ(a.camera.distortion, b.camera.distortion);
      const PoseDifference d = Difference(a.cam_from_obj, b.cam_from_obj);
      EXPECT_LT(d.translation, 1e-7);
      EXPECT_LT(d.rotation_rad, 1e-9);
      EXPECT_LE(cv::norm(a.image, b.image, cv::NORM_INF), 0.5 / 255 + 1e-6);
      ASSERT_EQ(a.depth.empty(), b.depth.empty());
      if (!a.depth.empty()) {
        EXPECT_LE(cv::norm(a.depth, b.depth, cv::NORM_INF), 1e-5);  // 60 000 counts to 0.5 m
        EXPECT_EQ(b.depth.at<float>(3, 0), 0.0f);
        EXPECT_NEAR(b.depth_tolerance_m, 0.004f, 1e-7f);
      }
    }
  }
  // Saving a mesh without projectors removes a stale projector file.
  mesh.projectors.clear();
  SaveMesh(mesh, Path("proj.ply"));
  EXPECT_FALSE(fs::exists(Path("proj_projectors.json")));
  EXPECT_TRUE(LoadMesh(Path("proj.ply")).projectors.empty());
}

TEST_F(MeshIoTest, BadProjectorFileThrowsNamingField) {
  Mesh mesh = ColouredTetrahedron();
  SaveMesh(mesh, Path("p.ply"));
  const std::string json_path = Path("p_projectors.json");
  Write("p_projectors.json", "{ not json");
  ExpectThrowsMentioning([&] { LoadMesh(Path("p.ply")); }, {json_path, "malformed"});
  Write("p_projectors.json", R"({"projectors": [{"image": "x.png"}]})");
  ExpectThrowsMentioning([&] { LoadMesh(Path("p.ply")); }, {json_path, "camera"});
  Write("p_projectors.json", R"({"projectors": [{"image": "x.png",
      "camera": {"width": 4, "height": 3, "fx": 5, "fy": 5, "cx": 2, "cy": 1},
      "cam_from_obj": {"rotation": [[1, 0, 0], [0, 1, 0], [0, 0, 2]], "translation": [0, 0, 1]}}]})");
  ExpectThrowsMentioning([&] { LoadMesh(Path("p.ply")); }, {json_path, "rotation"});
  Write("p_projectors.json", R"({"projectors": [{"image": "x.png",
      "camera": {"width": 4, "height": 3, "fx": 5, "fy": 5, "cx": 2, "cy": 1},
      "cam_from_obj": {"rotation": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "translation": [0, 0, 1]}}]})");
  ExpectThrowsMentioning([&] { LoadMesh(Path("p.ply")); }, {json_path, "x.png"});
}

TEST_F(MeshIoTest, SaveRejectsBadInput) {
  const Mesh good = ColouredTetrahedron();
  ExpectThrowsMentioning([&] { SaveMesh(good, Path("m.stl")); }, {"m.stl", ".ply or .obj"});
  EXPECT_THROW(SaveMesh(good, Path("m.ply"), 0.0), Error);
  Mesh bad = good;
  bad.vertices[1].x() = std::numeric_limits<float>::quiet_NaN();
  ExpectThrowsMentioning([&] { SaveMesh(bad, Path("bad.ply")); }, {"bad.ply", "vertex 1"});
  EXPECT_THROW(SaveMesh(Mesh(), Path("empty.ply")), Error);
  // Saving into a folder that does not exist yet creates it.
  SaveMesh(good, Path("sub/dir/m.ply"));
  EXPECT_EQ(LoadMesh(Path("sub/dir/m.ply")).num_triangles(), 4);
}

}  // namespace
}  // namespace unseen
