// The outline pixels (scene/edges.h) against an independent test of which side of a sphere's silhouette
// cone a ray lies on, a window against the whole image, and surfaces in front.
#include "scene/edges.h"

#include <gtest/gtest.h>

#include <cmath>

#include "support/scenes.h"

namespace nimbus {
namespace {

constexpr int kW = 41, kH = 31;

Scene sphere_scene(const std::string& more = "") {
  return test::scene_from_json("{" + test::camera_json(kW, kH, 30.0, 5.0) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0.3, 0, 0.1], "radius": 1}, "sigma_s": 4.0}],
    "lights": [{"type": "directional", "direction": [0, 1, 0], "irradiance": 1}])" +
                               more + "}");
}

// Whether the ray from the camera (0, -5, 0) along d passes within the sphere's silhouette cone: the angle
// to its centre below asin(r / distance).
bool in_cone(const Vec3& d) {
  const Vec3 to_c = Vec3(0.3, 0, 0.1) - Vec3(0, -5, 0);
  const double dist = length(to_c), cos_cone = std::sqrt(1.0 - 1.0 / (dist * dist));
  return dot(normalize(d), to_c) / dist > cos_cone;
}

TEST(Edges, OutlinePixelsAreThoseTheSilhouetteCrosses) {
  const SceneContext ctx(sphere_scene());
  const std::vector<PixelEdge> e = edge_pixels(ctx, Region{0, 0, kW, kH});
  ASSERT_EQ(e.size(), size_t(kW * kH));
  auto corners_differ = [&](int x, int y) {
    const bool a = in_cone(ctx.camera.direction(x, y));
    return in_cone(ctx.camera.direction(x + 1, y)) != a || in_cone(ctx.camera.direction(x, y + 1)) != a ||
           in_cone(ctx.camera.direction(x + 1, y + 1)) != a;
  };
  int outline = 0, mixed = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      bool beside = false;
      for (int v = std::max(y - 1, 0); v <= std::min(y + 1, kH - 1); ++v)
        for (int u = std::max(x - 1, 0); u <= std::min(x + 1, kW - 1); ++u) beside |= corners_differ(u, v);
      const PixelEdge want = corners_differ(x, y) ? PixelEdge::outline
                             : beside             ? PixelEdge::beside
                                                  : PixelEdge::none;
      EXPECT_EQ(int(e[size_t(y) * kW + x]), int(want)) << x << " " << y;
      outline += want == PixelEdge::outline;
      // Every pixel the silhouette crosses (seen on a 9 x 9 grid of points in it) takes more samples.
      int inside = 0;
      for (int j = 0; j <= 8; ++j)
        for (int i = 0; i <= 8; ++i) inside += in_cone(ctx.camera.direction(x + i / 8.0, y + j / 8.0));
      if (inside > 0 && inside < 81) {
        ++mixed;
        EXPECT_NE(int(e[size_t(y) * kW + x]), int(PixelEdge::none)) << x << " " << y;
      }
    }
  EXPECT_GT(outline, 40);  // the silhouette, about 20 pixels across, crosses ~2 pi 10 pixels
  EXPECT_GE(mixed, outline);
}

TEST(Edges, AWindowsClassesAreThoseOfTheWholeImage) {
  const SceneContext ctx(sphere_scene());
  const std::vector<PixelEdge> whole = edge_pixels(ctx, Region{0, 0, kW, kH});
  // A window the outline crosses, its borders through outline pixels, and one at the image's corner.
  for (const Region& w : {Region{7, 4, 23, 19}, Region{0, 0, 14, 12}, Region{30, 20, kW, kH}}) {
    const std::vector<PixelEdge> part = edge_pixels(ctx, w);
    ASSERT_EQ(part.size(), size_t((w.x1 - w.x0) * (w.y1 - w.y0)));
    int outline = 0;
    for (int y = w.y0; y < w.y1; ++y)
      for (int x = w.x0; x < w.x1; ++x) {
        const PixelEdge p = part[size_t(y - w.y0) * (w.x1 - w.x0) + (x - w.x0)];
        EXPECT_EQ(int(p), int(whole[size_t(y) * kW + x])) << x << " " << y;
        outline += p == PixelEdge::outline;
      }
    EXPECT_GT(outline, 2) << w.x0 << " " << w.y0;
  }
}

TEST(Edges, AMediumsTransformMovesItsOutline) {
  // The sphere of sphere_scene() (centre (0.3, 0, 0.1)) made as a unit sphere at the origin, scaled by 1
  // and moved there by its transform: the same classes. Moved elsewhere: others.
  const std::string moved = R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 4.0,
               "transform": {"translate": [0.3, 0, 0.1]}}],
    "lights": [{"type": "directional", "direction": [0, 1, 0], "irradiance": 1}]})";
  const SceneContext a(sphere_scene()),
      b(test::scene_from_json("{" + test::camera_json(kW, kH, 30.0, 5.0) + moved));
  const Region all{0, 0, kW, kH};
  const std::vector<PixelEdge> ea = edge_pixels(a, all), eb = edge_pixels(b, all);
  int differ = 0;
  for (size_t i = 0; i < ea.size(); ++i) differ += ea[i] != eb[i];
  EXPECT_LE(differ, 2);  // corner rays within rounding of the silhouette may fall either way
  std::string shifted = moved;
  shifted.replace(shifted.find("0.3, 0, 0.1"), 11, "0.6, 0, 0.1");
  const SceneContext c(test::scene_from_json("{" + test::camera_json(kW, kH, 30.0, 5.0) + shifted));
  const std::vector<PixelEdge> ec = edge_pixels(c, all);
  differ = 0;
  for (size_t i = 0; i < ea.size(); ++i) differ += ea[i] != ec[i];
  EXPECT_GT(differ, 20);
}

TEST(Edges, ASurfaceInFrontHidesTheOutlineBehindIt) {
  // An opaque rectangle between the camera and the sphere over the image's left half: its edge runs down
  // the middle column; the sphere's outline shows only on the right.
  const SceneContext ctx(sphere_scene(R"(,
    "surfaces": [{"shape": {"type": "rectangle", "center": [-1, -2, 0], "normal": [0, 1, 0], "up": [0, 0, 1],
                            "size": [2, 10]}, "material": {"type": "diffuse", "albedo": 0.5}}])"));
  const std::vector<PixelEdge> e = edge_pixels(ctx, Region{0, 0, kW, kH});
  int right = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const PixelEdge p = e[size_t(y) * kW + x];
      if (x == kW / 2) EXPECT_EQ(int(p), int(PixelEdge::outline)) << x << " " << y;
      if (x < kW / 2 - 1) EXPECT_EQ(int(p), int(PixelEdge::none)) << x << " " << y;
      if (x > kW / 2 + 1) right += p == PixelEdge::outline;
    }
  EXPECT_GT(right, 15);
}

TEST(Edges, ADensityGridHasNoOutline) {
  const SceneContext ctx(test::scene_from_json("{" + test::camera_json(kW, kH, 30.0, 5.0) + R"(,
    "media": [{"shape": {"type": "cloud", "radius": 0.8, "resolution": 12}, "sigma_s": 2}],
    "lights": [{"type": "directional", "direction": [0, 1, 0], "irradiance": 1}]})"));
  for (PixelEdge p : edge_pixels(ctx, Region{0, 0, kW, kH})) EXPECT_EQ(int(p), int(PixelEdge::none));
}

}  // namespace
}  // namespace nimbus
