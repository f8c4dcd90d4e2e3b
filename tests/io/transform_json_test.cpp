// The `transform` block: Transform's algebra (inverse, composition, normals, exact quarter turns), the
// scene's two forms checked on points against hand-computed maps (scale, then the rotations in order,
// then the translation), the matrix form against the equivalent SRT form, and every error naming the
// file and the JSON path (and exit code 2 from the CLI).
#include "io/transform_json.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>

#include "core/json_reader.h"
#include "core/math.h"
#include "nimbus/error.h"
#include "nimbus/transform.h"
#include "support/scenes.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

Transform parse(const std::string& text) {
  const nlohmann::json j = nlohmann::json::parse(text);
  return parse_transform(JsonObject(j, "scene.json", "/media/0/transform"));
}

std::string transform_error(const std::string& text) {
  try {
    parse(text);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

void expect_near(const Vec3& a, const Vec3& b, double tol = 1e-12) {
  EXPECT_NEAR(a.x, b.x, tol) << a << " vs " << b;
  EXPECT_NEAR(a.y, b.y, tol) << a << " vs " << b;
  EXPECT_NEAR(a.z, b.z, tol) << a << " vs " << b;
}

// Rodrigues by hand, independent of Transform: v rotated by `deg` degrees about the unit axis a.
Vec3 rotate(const Vec3& v, const Vec3& axis, double deg) {
  const Vec3 a = normalize(axis);
  const double t = deg * kPi / 180.0;
  return v * std::cos(t) + cross(a, v) * std::sin(t) + a * (dot(a, v) * (1.0 - std::cos(t)));
}

const Vec3 kPoints[] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.3, -1.7, 2.2}, {-4, 5, -6}};

TEST(Transform, IdentityAndElementaryMaps) {
  const Transform id;
  EXPECT_TRUE(id.is_identity());
  EXPECT_EQ(id.determinant(), 1.0);
  EXPECT_EQ(id.point(Vec3(1, 2, 3)), Vec3(1, 2, 3));
  EXPECT_TRUE(Transform::translation(Vec3(0.0)).is_identity());
  EXPECT_FALSE(Transform::translation(Vec3(0, 0, 1e-300)).is_identity());
  const Transform s = Transform::scaling(Vec3(2, -3, 0.5));
  EXPECT_EQ(s.point(Vec3(1, 1, 1)), Vec3(2, -3, 0.5));
  EXPECT_DOUBLE_EQ(s.determinant(), -3.0);
  const Transform t = Transform::translation(Vec3(1, 2, 3));
  EXPECT_EQ(t.point(Vec3(1, 1, 1)), Vec3(2, 3, 4));
  EXPECT_EQ(t.vector(Vec3(1, 1, 1)), Vec3(1, 1, 1));  // vectors do not move
  // Right-handed quarter turns, exact: about x, y -> z; about z, x -> y.
  EXPECT_EQ(Transform::rotation(Vec3(1, 0, 0), 90).point(Vec3(0, 1, 0)), Vec3(0, 0, 1));
  EXPECT_EQ(Transform::rotation(Vec3(1, 0, 0), 90).point(Vec3(0, 0, 1)), Vec3(0, -1, 0));
  EXPECT_EQ(Transform::rotation(Vec3(0, 0, 2), 90).point(Vec3(1, 0, 0)), Vec3(0, 1, 0));
  EXPECT_EQ(Transform::rotation(Vec3(0, 1, 0), -270).point(Vec3(0, 0, 1)), Vec3(1, 0, 0));
  EXPECT_EQ(Transform::rotation(Vec3(0, 1, 0), 180).point(Vec3(1, 2, 3)), Vec3(-1, 2, -3));
  EXPECT_TRUE(Transform::rotation(Vec3(1, 1, 1), 720).is_identity());
  for (const Vec3& p : kPoints)
    expect_near(Transform::rotation(Vec3(1, 2, -3), 37).point(p), rotate(p, Vec3(1, 2, -3), 37));
}

TEST(Transform, InverseCompositionAndNormals) {
  const Transform a = Transform::scaling(Vec3(2, 0.5, -1.5))
                          .then(Transform::rotation(Vec3(0.2, 1, 0.3), 41))
                          .then(Transform::translation(Vec3(3, -1, 2)));
  const Transform inv = a.inverse();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-5, 5);
  for (int k = 0; k < 100; ++k) {
    const Vec3 p(u(rng), u(rng), u(rng)), v(u(rng), u(rng), u(rng));
    expect_near(inv.point(a.point(p)), p, 1e-12);
    expect_near(a.point(inv.point(p)), p, 1e-12);
    expect_near(a.vector(v), a.point(v) - a.point(Vec3(0.0)), 1e-12);
    // A normal stays perpendicular to every transformed tangent.
    const Vec3 n = normalize(Vec3(u(rng), u(rng), u(rng)));
    const Vec3 tangent = cross(n, v);
    EXPECT_NEAR(dot(a.normal(n), a.vector(tangent)), 0.0, 1e-10);
  }
  EXPECT_NEAR(a.determinant() * inv.determinant(), 1.0, 1e-12);
  EXPECT_NEAR(a.determinant(), 2 * 0.5 * -1.5, 1e-12);
  // then(): this first, then next.
  const Transform s = Transform::scaling(Vec3(2.0)), t = Transform::translation(Vec3(1, 0, 0));
  EXPECT_EQ(s.then(t).point(Vec3(1, 1, 1)), Vec3(3, 2, 2));
  EXPECT_EQ(t.then(s).point(Vec3(1, 1, 1)), Vec3(4, 2, 2));
  expect_near(s.then(t).then(t.then(s).inverse()).point(Vec3(1, 1, 1)), Vec3(0.5, 1, 1));
  // from_matrix with a raw array, as the API promises.
  const double m[3][4] = {{0, -1, 0, 1}, {1, 0, 0, 2}, {0, 0, 1, 3}};
  EXPECT_EQ(Transform::from_matrix(m).point(Vec3(1, 0, 0)), Vec3(1, 3, 3));
  const double singular[3][4] = {{1, 2, 3, 0}, {2, 4, 6, 0}, {0, 0, 1, 0}};
  EXPECT_THROW(Transform::from_matrix(singular), Error);
}

TEST(TransformJson, EachFormMapsPointsAsWritten) {
  // Scale alone: uniform and per axis.
  for (const Vec3& p : kPoints) {
    expect_near(parse(R"({"scale": 2})").point(p), p * 2.0);
    expect_near(parse(R"({"scale": [1, -2, 3]})").point(p), Vec3(p.x, -2 * p.y, 3 * p.z));
    expect_near(parse(R"({"translate": [1, 2, 3]})").point(p), p + Vec3(1, 2, 3));
    expect_near(parse(R"({"rotate": [{"axis": [0, 0, 5], "degrees": 30}]})").point(p),
                rotate(p, {0, 0, 1}, 30));
  }
  EXPECT_TRUE(parse("{}").is_identity());
  EXPECT_TRUE(parse(R"({"rotate": []})").is_identity());
  // All three: scale first, then the rotations in the order written, then the translation.
  const Transform t = parse(R"({"scale": [2, 1, 0.5],
      "rotate": [{"axis": [1, 0, 0], "degrees": 90}, {"axis": [0, 0, 1], "degrees": 90}],
      "translate": [10, 20, 30]})");
  // By hand: (1, 2, 4) -> scale (2, 2, 2) -> about x (2, -2, 2) -> about z (2, 2, 2) -> (12, 22, 32).
  EXPECT_EQ(t.point(Vec3(1, 2, 4)), Vec3(12, 22, 32));
  // (1, 0, 0) -> (2, 0, 0) -> (2, 0, 0) -> (0, 2, 0) -> (10, 22, 30). The other order of the rotations
  // would give (0, 0, 2) + t: the order matters and is the written one.
  EXPECT_EQ(t.point(Vec3(1, 0, 0)), Vec3(10, 22, 30));
  for (const Vec3& p : kPoints) {
    const Vec3 expected =
        rotate(rotate(Vec3(2 * p.x, p.y, 0.5 * p.z), {1, 0, 0}, 90), {0, 0, 1}, 90) + Vec3(10, 20, 30);
    expect_near(t.point(p), expected, 1e-12);
  }
  // Arbitrary angles, two rotations about skew axes.
  const Transform u = parse(R"({"scale": 1.5, "rotate": [{"axis": [1, 2, 3], "degrees": 25},
      {"axis": [-1, 0, 1], "degrees": -70}], "translate": [0, 1, 0]})");
  for (const Vec3& p : kPoints)
    expect_near(u.point(p), rotate(rotate(p * 1.5, {1, 2, 3}, 25), {-1, 0, 1}, -70) + Vec3(0, 1, 0), 1e-12);
}

TEST(TransformJson, MatrixFormEqualsTheSrtForm) {
  const Transform srt = parse(R"({"scale": [2, 3, 4], "rotate": [{"axis": [0, 1, 1], "degrees": 33}],
      "translate": [-1, 0.5, 7]})");
  // The matrix written out by hand from the SRT form's columns (images of the unit vectors).
  const Vec3 c0 = rotate({2, 0, 0}, {0, 1, 1}, 33), c1 = rotate({0, 3, 0}, {0, 1, 1}, 33),
             c2 = rotate({0, 0, 4}, {0, 1, 1}, 33);
  const std::string text = fmt::format(
      R"({{"matrix": [[{:.17g}, {:.17g}, {:.17g}, -1], [{:.17g}, {:.17g}, {:.17g}, 0.5],
                      [{:.17g}, {:.17g}, {:.17g}, 7], [0, 0, 0, 1]]}})",
      c0.x, c1.x, c2.x, c0.y, c1.y, c2.y, c0.z, c1.z, c2.z);
  const Transform mat = parse(text);
  for (const Vec3& p : kPoints) {
    expect_near(mat.point(p), srt.point(p), 1e-12);
    expect_near(mat.inverse().point(p), srt.inverse().point(p), 1e-12);
  }
  EXPECT_TRUE(parse(R"({"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]})").is_identity());
}

TEST(TransformJson, ErrorsNameTheFileAndThePath) {
  const std::string p = "scene.json: /media/0/transform";
  EXPECT_EQ(transform_error(R"({"scale": 0})"), p + "/scale: must not be zero");
  EXPECT_EQ(transform_error(R"({"scale": [1, 0, 1]})"), p + "/scale/1: must not be zero");
  EXPECT_EQ(transform_error(R"({"scale": "big"})"), p + "/scale: must be a number or an array [sx, sy, sz]");
  EXPECT_EQ(transform_error(R"({"scale": [1, 2]})"), p + "/scale: must be an array of 3 numbers");
  EXPECT_EQ(transform_error(R"({"scale": [1e-200, 1e-200, 1]})"),
            p + "/scale: must give an invertible transform (components too small or too large)");
  EXPECT_EQ(transform_error(
                R"({"rotate": [{"axis": [1, 0, 0], "degrees": 5}, {"axis": [0, 0, 0], "degrees": 5}]})"),
            p + "/rotate/1/axis: must have non-zero length");
  EXPECT_EQ(transform_error(R"({"rotate": [{"axis": [1, 0, 0]}]})"),
            p + "/rotate/0/degrees: required field is missing");
  EXPECT_EQ(transform_error(R"({"rotate": [{"axis": [1, 0, 0], "degrees": 5, "angle": 1}]})"),
            p + "/rotate/0/angle: unknown field (known here: axis, degrees)");
  EXPECT_EQ(transform_error(R"({"rotate": {"axis": [1, 0, 0], "degrees": 5}})"),
            p + "/rotate: must be an array, not an object");
  EXPECT_EQ(transform_error(R"({"translate": [1, 2, "x"]})"),
            p + "/translate/2: must be a number, not a string");
  EXPECT_EQ(transform_error(R"({"translation": [1, 2, 3]})"),
            p + "/translation: unknown field (known here: matrix, rotate, scale, translate)");
  // The matrix form.
  EXPECT_EQ(transform_error(R"({"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]]})"),
            p + "/matrix/3: must be [0, 0, 0, 1] (an affine map)");
  EXPECT_EQ(transform_error(R"({"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]})"),
            p + "/matrix: must be an array of 4 rows of 4 numbers");
  EXPECT_EQ(transform_error(R"({"matrix": [[1, 0, 0, 0], [0, 1, 0], [0, 0, 1, 0], [0, 0, 0, 1]]})"),
            p + "/matrix/1: must be an array of 4 numbers");
  EXPECT_EQ(transform_error(R"({"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, null, 0], [0, 0, 0, 1]]})"),
            p + "/matrix/2/2: must be a number");
  EXPECT_EQ(transform_error(R"({"matrix": [[1, 2, 3, 0], [2, 4, 6, 0], [0, 0, 1, 0], [0, 0, 0, 1]]})"),
            p + "/matrix: must be finite and invertible (determinant 0)");
  EXPECT_EQ(
      transform_error(R"({"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], "scale": 2})"),
      p + "/scale: cannot be combined with \"matrix\" (use one form or the other)");
  EXPECT_EQ(transform_error(
                R"({"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], "rotate": []})"),
            p + "/rotate: cannot be combined with \"matrix\" (use one form or the other)");
  // NaN cannot be written in JSON text, but a document built in memory can hold it.
  nlohmann::json nan_doc = nlohmann::json::parse(R"({"rotate": [{"axis": [1, 0, 0], "degrees": 0}]})");
  nan_doc["rotate"][0]["degrees"] = std::nan("");
  try {
    parse_transform(JsonObject(nan_doc, "scene.json", "/media/0/transform"));
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), p + "/rotate/0/degrees: must be finite");
  }
  nlohmann::json nan_matrix =
      nlohmann::json::parse(R"({"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]})");
  nan_matrix["matrix"][1][3] = std::nan("");
  try {
    parse_transform(JsonObject(nan_matrix, "scene.json", "/media/0/transform"));
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), p + "/matrix/1/3: must be finite");
  }
}

// In a scene: the field of every medium type, after the shape's own fields; the vdb scale is optional.
TEST(TransformJson, EveryMediumTakesATransform) {
  const std::string head = "{" + test::camera_json() + R"(, "lights": [], "media": [)";
  const Scene s = test::scene_from_json(head + R"(
      {"shape": {"type": "sphere", "radius": 1}, "sigma_s": 1, "transform": {"translate": [1, 0, 0]}},
      {"shape": {"type": "box", "min": [0, 0, 0], "max": [1, 1, 1]}, "sigma_s": 1, "transform": {"scale": 2}},
      {"shape": {"type": "cloud", "radius": 1, "resolution": 8}, "sigma_s": 1,
       "transform": {"rotate": [{"axis": [0, 0, 1], "degrees": 90}]}},
      {"shape": {"type": "sphere", "radius": 1}, "sigma_s": 1}]})");
  ASSERT_EQ(s.media.size(), 4u);
  EXPECT_EQ(s.media[0].transform.point(Vec3(0.0)), Vec3(1, 0, 0));
  EXPECT_EQ(s.media[1].transform.point(Vec3(1.0)), Vec3(2.0));
  EXPECT_EQ(s.media[2].transform.point(Vec3(1, 0, 0)), Vec3(0, 1, 0));
  EXPECT_TRUE(s.media[3].transform.is_identity());
  try {
    test::scene_from_json(head + R"({"shape": {"type": "sphere", "radius": 1}, "sigma_s": 1},
        {"shape": {"type": "sphere", "radius": 1}, "sigma_s": 1,
         "transform": {"rotate": [{"axis": [0, 0, 1], "degrees": 9}, {"axis": [0, 0, 0], "degrees": 9}]}}]})");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "test.json: /media/1/transform/rotate/1/axis: must have non-zero length");
  }
}

TEST(TransformJson, TheCliRefusesASingularTransformWithExitCode2) {
  test::ScratchDir dir("xform_cli");
  std::ofstream(dir / "s.json") << "{" + test::camera_json() + R"(, "lights": [],
      "media": [{"shape": {"type": "box", "min": [0, 0, 0], "max": [1, 1, 1]}, "sigma_s": 1,
                 "transform": {"matrix": [[1, 0, 0, 0], [0, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}}]})";
  const std::string cmd =
      fmt::format("{} render {} -o {} --quiet 2> {}", NIMBUS_CLI, (dir / "s.json").string(),
                  (dir / "o.exr").string(), (dir / "err.txt").string());
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::ifstream err(dir / "err.txt");
  const std::string text{std::istreambuf_iterator<char>(err), std::istreambuf_iterator<char>()};
  EXPECT_NE(text.find("s.json: /media/0/transform/matrix: must be finite and invertible"), std::string::npos)
      << text;
  EXPECT_FALSE(std::filesystem::exists(dir / "o.exr"));
}

}  // namespace
}  // namespace nimbus
