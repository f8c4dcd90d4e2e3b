// The OBJ mesh loader (src/io/mesh.cpp): what a good file gives (quads triangulated, vertex normals
// kept only when every corner has one, positions as written) and the exact error for each kind of bad
// file (unreadable, empty, garbage, no faces, non-finite or huge coordinates, degenerate triangles,
// indices out of range). Every error starts with the file's name as the scene wrote it.
#include "io/mesh.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "nimbus/error.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

namespace fs = std::filesystem;

// The unit cube as 8 vertices and 6 quads (outward, counter-clockwise), as most exporters write it.
constexpr const char* kCubeQuads = R"(# cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
)";

constexpr const char* kTriangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

std::string mesh_error(const std::string& text) {
  try {
    mesh_from_obj_text(text, "cube.obj");
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

std::string mesh_load_error(const fs::path& file, const std::string& name) {
  try {
    load_mesh(file, name);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

// Three vertices (one replaced by `line`) and the face 1 2 3.
std::string triangle_with_vertex(const std::string& line) { return line + "\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"; }

TEST(Mesh, AQuadGivesTwoTriangles) {
  const TriangleMesh m = mesh_from_obj_text("v 0 0 0\nv 2 0 0\nv 2 3 0\nv 0 3 0\nf 1 2 3 4\n", "q.obj");
  EXPECT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.triangle_count(), 2u);
  EXPECT_TRUE(m.normals.empty());
  // The two triangles cover the quad: their areas add up to 2 x 3.
  double area = 0.0;
  for (size_t t = 0; t < m.triangle_count(); ++t) {
    const Vec3 a = m.position(m.indices[3 * t]), b = m.position(m.indices[3 * t + 1]);
    const Vec3 c = m.position(m.indices[3 * t + 2]);
    area += 0.5 * length(cross(b - a, c - a));
  }
  EXPECT_DOUBLE_EQ(area, 6.0);
}

TEST(Mesh, CubeOfQuadsGivesTwelveTrianglesOverItsEightVertices) {
  const TriangleMesh m = mesh_from_obj_text(kCubeQuads, "cube.obj");
  EXPECT_EQ(m.vertex_count(), 8u);
  EXPECT_EQ(m.triangle_count(), 12u);
  for (uint32_t i : m.indices) EXPECT_LT(i, 8u);
}

TEST(Mesh, VertexCountAndPositionsAsWritten) {
  const TriangleMesh m =
      mesh_from_obj_text("v -1.5 2.25e2 +3\nv 1e15 -.5 0.0\n  v\t7 8 9 1.0\nf 1 2 3\n", "p.obj");
  ASSERT_EQ(m.vertex_count(), 3u);
  EXPECT_EQ(m.position(0), Vec3(-1.5, 225.0, 3.0));
  EXPECT_EQ(m.position(1), Vec3(double(float(1e15)), -0.5, 0.0));  // kMaxMeshCoordinate itself is allowed
  EXPECT_EQ(m.position(2), Vec3(7.0, 8.0, 9.0));                   // an optional w is ignored
}

TEST(Mesh, RelativeIndicesCountBackFromTheLastVertex) {
  const TriangleMesh m = mesh_from_obj_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n", "r.obj");
  ASSERT_EQ(m.triangle_count(), 1u);
  EXPECT_EQ(m.position(m.indices[1]), Vec3(1.0, 0.0, 0.0));
}

TEST(Mesh, VertexNormalsAreKeptWhenEveryCornerHasOne) {
  const TriangleMesh m = mesh_from_obj_text(
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvn 0 0.6 0.8\nf 1//1 2//1 3//2 4//2\n", "n.obj");
  EXPECT_EQ(m.triangle_count(), 2u);
  ASSERT_EQ(m.normals.size(), 3 * m.vertex_count());
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const Vec3 expected =
        m.position(v).y == 0.0 ? Vec3(0.0, 0.0, 1.0) : Vec3(0.0, double(0.6f), double(0.8f));
    EXPECT_EQ(m.normal(v), expected) << "vertex " << v;
  }
}

TEST(Mesh, UnusableVertexNormalsAreStoredAsZero) {
  // tinyobjloader reads 32-bit floats: 1e40 is infinite. A zero normal makes the hit use the face's.
  const TriangleMesh m = mesh_from_obj_text(
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 2\nvn 1e40 0 0\nvn 0 0 0\nf 1//1 2//2 3//3\n", "u.obj");
  ASSERT_EQ(m.normals.size(), 9u);
  EXPECT_EQ(m.normal(0), Vec3(0, 0, 2));
  EXPECT_EQ(m.normal(1), Vec3(0, 0, 0));
  EXPECT_EQ(m.normal(2), Vec3(0, 0, 0));
}

TEST(Mesh, OneVertexWithTwoNormalsBecomesTwoVertices) {
  // Vertices 1 and 3 are used with normal 1 by the first triangle and normal 2 by the second: a hard edge.
  const TriangleMesh m = mesh_from_obj_text(
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nvn 1 0 0\nf 1//1 2//1 3//1\nf 1//2 3//2 4//2\n",
      "h.obj");
  EXPECT_EQ(m.triangle_count(), 2u);
  EXPECT_EQ(m.vertex_count(), 6u);  // vertices 1 and 3 appear with both normals
  EXPECT_EQ(m.normals.size(), 18u);
}

TEST(Mesh, VertexNormalsAreDroppedWhenAnyCornerLacksOne) {
  const TriangleMesh m = mesh_from_obj_text(
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf 1 3 4\n", "d.obj");
  EXPECT_EQ(m.triangle_count(), 2u);
  EXPECT_EQ(m.vertex_count(), 4u);
  EXPECT_TRUE(m.normals.empty());
}

TEST(Mesh, TextureCoordinatesGroupsObjectsAndMaterialsAreIgnored) {
  const TriangleMesh m = mesh_from_obj_text(R"(mtllib scene.mtl
o thing
g top
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
usemtl red
s 1
f 1/1/1 2/2/1 3/3/1
g bottom
f 1/1 3/3 4/4
)",
                                            "t.obj");
  EXPECT_EQ(m.triangle_count(), 2u);
  EXPECT_EQ(m.vertex_count(), 4u);
  EXPECT_TRUE(m.normals.empty());  // the second face has no normals
}

TEST(Mesh, CrLfLineEndsAndCommentsRead) {
  const TriangleMesh m =
      mesh_from_obj_text("# made on Windows\r\nv 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n", "w.obj");
  EXPECT_EQ(m.triangle_count(), 1u);
}

TEST(Mesh, SmallTrianglesAreNotDegenerate) {
  // The degeneracy test is relative to the edges' lengths: a micrometre triangle far from the origin is fine.
  const TriangleMesh m = mesh_from_obj_text("v 1000 0 0\nv 1000.001 0 0\nv 1000 0.001 0\nf 1 2 3\n", "s.obj");
  EXPECT_EQ(m.triangle_count(), 1u);
}

TEST(MeshErrors, EmptyGarbageAndVertexOnlyFilesHaveNoTriangles) {
  EXPECT_EQ(mesh_error(""), "cube.obj: the mesh has no triangles");
  EXPECT_EQ(mesh_error("\n\n# only a comment\n"), "cube.obj: the mesh has no triangles");
  EXPECT_EQ(mesh_error(std::string("\x7f"
                                   "ELF\x02\x01\x01\0\0\0\xff\xfe garbage\n\x01\x02",
                                   22)),
            "cube.obj: the mesh has no triangles");
  EXPECT_EQ(mesh_error("v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "cube.obj: the mesh has no triangles");
  EXPECT_EQ(mesh_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\n"), "cube.obj: the mesh has no triangles");
}

TEST(MeshErrors, NonFiniteCoordinatesAreErrorsNotZeros) {
  // tinyobjloader itself reads these as 0 (bug found by this test: the mesh loaded, silently changed).
  EXPECT_EQ(mesh_error(triangle_with_vertex("v nan 0 0")),
            "cube.obj: line 1: vertex coordinate 'nan' is not finite");
  EXPECT_EQ(mesh_error(triangle_with_vertex("v 0 -inf 0")),
            "cube.obj: line 1: vertex coordinate '-inf' is not finite");
  EXPECT_EQ(mesh_error(triangle_with_vertex("v 0 0 infinity")),
            "cube.obj: line 1: vertex coordinate 'infinity' is not finite");
  EXPECT_EQ(mesh_error("v 0 0 0\r\nv 1 NaN 0\r\nv 0 1 0\r\nf 1 2 3\r\n"),
            "cube.obj: line 2: vertex coordinate 'NaN' is not finite");
}

TEST(MeshErrors, MalformedCoordinatesAreErrors) {
  EXPECT_EQ(mesh_error(triangle_with_vertex("v 1,5 0 0")),
            "cube.obj: line 1: vertex coordinate '1,5' is not a number");
  EXPECT_EQ(mesh_error(triangle_with_vertex("v 0 0 1e")),
            "cube.obj: line 1: vertex coordinate '1e' is not a number");
  EXPECT_EQ(mesh_error(triangle_with_vertex("v 0 0x10 0")),
            "cube.obj: line 1: vertex coordinate '0x10' is not a number");
  EXPECT_EQ(mesh_error(triangle_with_vertex("v 0 0")), "cube.obj: line 1: a vertex needs 3 coordinates");
  EXPECT_EQ(mesh_error(triangle_with_vertex("v " + std::string(100, 'x') + " 0 0")),
            "cube.obj: line 1: vertex coordinate '" + std::string(32, 'x') + "...' is not a number");
  EXPECT_EQ(mesh_error(triangle_with_vertex(std::string("v 0 \x01\xff 0"))),
            "cube.obj: line 1: vertex coordinate '?"
            "?' is not a number");
}

TEST(Mesh, SkinWeightsAndTagsAreIgnored) {
  // Both are tinyobjloader extensions it mishandles: `vw` joint ids are converted to int unchecked (a
  // fuzz finding), and every `t` line allocated up to 8192 ints, reals and strings (2 GB and 100 s for
  // a 38 KB file). nimbus hides them from it as comments.
  const std::string weights = std::string(kTriangle) + "vw 1 1e300 0.5 1 0.5\n";
  EXPECT_EQ(mesh_from_obj_text(weights, "w.obj").triangle_count(), 1u);
  std::string tags = std::string(kTriangle) + "t crease 2/1/0 1 2 1.0\n";
  for (int i = 0; i < 2000; ++i) tags += "  t a 8192/8192/8192\n";
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(mesh_from_obj_text(tags, "t.obj").triangle_count(), 1u);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0);
  // Hidden lines keep their numbers: tinyobjloader's message names line 5.
  const std::string msg = mesh_error("v 0 0 0\nt x 1/0/0 5\nv 1 0 0\nv 0 1 0\nf 1 2 0\n");
  EXPECT_NE(msg.find("line 5"), std::string::npos) << msg;
}

TEST(MeshErrors, ExponentsOfTenDigitsAreErrors) {
  // tinyobjloader accumulates exponents in an int and overflowed at 2147483648 (fuzz finding).
  EXPECT_EQ(mesh_error(triangle_with_vertex("v 0 0 1e2147483648")),
            "cube.obj: line 1: number '1e2147483648' is out of range");
  EXPECT_EQ(mesh_error(std::string(kTriangle) + "vn 0 0 1E+0001000000000\n"),
            "cube.obj: line 5: number '1E+0001000000000' is out of range");
  EXPECT_EQ(mesh_error(std::string(kTriangle) + "vt 0.5 -1e-9999999999\n"),
            "cube.obj: line 5: number '-1e-9999999999' is out of range");
  // Nine digits are fine (a texture coordinate is not used), and so are leading zeros.
  EXPECT_EQ(mesh_error(std::string(kTriangle) + "vt 0.5 1e999999999\n"), "(no error)");
  EXPECT_EQ(mesh_error(triangle_with_vertex("v 0 0 1e-0000000000001")), "(no error)");
}

TEST(MeshErrors, HugeCoordinatesAreErrors) {
  // 2^52, exact as a float, beyond kMaxMeshCoordinate.
  EXPECT_EQ(mesh_error(triangle_with_vertex("v 0 -4503599627370496 0")),
            "cube.obj: vertex 1 has a coordinate -4503599627370496 (must be finite, at most 1e+15 in size)");
  // tinyobjloader reads 32-bit floats: beyond float range (and beyond double range) is infinite.
  EXPECT_EQ(mesh_error(triangle_with_vertex("v 1e300 0 0")),
            "cube.obj: vertex 1 has a coordinate inf (must be finite, at most 1e+15 in size)");
  EXPECT_EQ(mesh_error(triangle_with_vertex("v 0 0 -1e400")),
            "cube.obj: vertex 1 has a coordinate -inf (must be finite, at most 1e+15 in size)");
  // A vertex no face uses is not checked for size.
  EXPECT_EQ(mesh_error(std::string(kTriangle) + "v 1e300 0 0\n"), "(no error)");
}

TEST(MeshErrors, DegenerateTrianglesAreErrors) {
  EXPECT_EQ(mesh_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 1 2\n"),
            "cube.obj: triangle 2 is degenerate (zero area)");
  EXPECT_EQ(mesh_error("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"),
            "cube.obj: triangle 1 is degenerate (zero area)");
  EXPECT_EQ(mesh_error("v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n"),
            "cube.obj: triangle 1 is degenerate (zero area)");
  // Distinct vertices at the same place.
  EXPECT_EQ(mesh_error("v 0 0 0\nv 1 0 0\nv 0 0 0\nf 1 2 3\n"),
            "cube.obj: triangle 1 is degenerate (zero area)");
  // A quad with its four corners on a line: no triangle of it has an area.
  EXPECT_NE(mesh_error("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3 4\n").rfind("cube.obj: ", 0),
            std::string::npos);
  EXPECT_NE(mesh_error("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3 4\n"), "(no error)");
}

TEST(MeshErrors, IndicesOutOfRangeAreErrors) {
  EXPECT_EQ(mesh_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"), "cube.obj: a face refers to vertex 4 of 3");
  EXPECT_EQ(mesh_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n"),
            "cube.obj: a face refers to a vertex before the first one");
  EXPECT_EQ(mesh_error("f 1 2 3\n"), "cube.obj: a face refers to vertex 1 of 0");
  EXPECT_EQ(mesh_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n"),
            "cube.obj: a face refers to normal 2 of 1");
  // Index 0 does not exist in OBJ (indices start at 1): tinyobjloader's own message.
  EXPECT_EQ(
      mesh_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n").rfind("cube.obj: not a readable OBJ mesh: ", 0), 0u);
}

TEST(MeshFiles, LoadsAnObjFile) {
  const test::ScratchDir dir("mesh_load");
  std::ofstream(dir / "cube.obj") << kCubeQuads;
  const auto m = load_mesh(dir / "cube.obj", "cube.obj");
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->triangle_count(), 12u);
  // The extension in any case (bug found by this test: "CUBE.OBJ" was an unsupported format).
  std::ofstream(dir / "CUBE.OBJ") << kCubeQuads;
  EXPECT_EQ(load_mesh(dir / "CUBE.OBJ", "CUBE.OBJ")->triangle_count(), 12u);
}

TEST(MeshFiles, UnreadableFilesAreErrorsNamingTheFile) {
  const test::ScratchDir dir("mesh_files");
  EXPECT_EQ(mesh_load_error(dir / "missing.obj", "missing.obj"), "missing.obj: no such file");
  fs::create_directories(dir / "folder.obj");
  EXPECT_EQ(mesh_load_error(dir / "folder.obj", "folder.obj"), "folder.obj: is a directory");
  std::ofstream(dir / "cube.ply") << "ply\nformat ascii 1.0\nend_header\n";
  EXPECT_EQ(mesh_load_error(dir / "cube.ply", "cube.ply"),
            "cube.ply: unsupported mesh format '.ply' (supported: .obj)");
  EXPECT_EQ(mesh_load_error(dir / "cube", "cube"), "cube: unsupported mesh format '' (supported: .obj)");
  // A FIFO blocked the read until something wrote to it (bug found by this test); devices likewise.
  ASSERT_EQ(::mkfifo((dir / "pipe.obj").c_str(), 0600), 0);
  EXPECT_EQ(mesh_load_error(dir / "pipe.obj", "pipe.obj"), "pipe.obj: not a regular file");
  std::ofstream(dir / "empty.obj").flush();
  EXPECT_EQ(mesh_load_error(dir / "empty.obj", "empty.obj"), "empty.obj: the mesh has no triangles");
  {
    std::ofstream out(dir / "random.obj", std::ios::binary);
    uint32_t x = 12345;
    for (int i = 0; i < 4096; ++i) {
      x = x * 1664525u + 1013904223u;
      out.put(char(x >> 24));
    }
  }
  EXPECT_EQ(mesh_load_error(dir / "random.obj", "random.obj").rfind("random.obj: ", 0), 0u);
  std::ofstream(dir / "nan.obj") << triangle_with_vertex("v 0 nan 0");
  EXPECT_EQ(mesh_load_error(dir / "nan.obj", "meshes/nan.obj"),
            "meshes/nan.obj: line 1: vertex coordinate 'nan' is not finite");
}

}  // namespace
}  // namespace nimbus
