// Media under a transform: a vdb volume rotated by 90 degrees about x is the same volume stored Y-up
// (density at many points, and path-traced and single-scattered pixels), a rotated scene with its camera
// and lights rotated alike renders the same image (per-pixel test against the estimated noise, with a
// negative control), analytic shapes map as the hand-computed ellipsoid, and max_density stays
// conservative in random boxes under rotations with non-uniform scale.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nanovdb/util/GridBuilder.h>
#include <nanovdb/util/IO.h>

#include <cmath>
#include <functional>
#include <random>

#include "integrators/pathtrace.h"
#include "integrators/single.h"
#include "media/density_grid.h"
#include "media/majorant.h"
#include "media/media.h"
#include "nimbus/render.h"
#include "scene/context.h"
#include "support/scenes.h"
#include "support/scratch_dir.h"
#include "support/stats.h"

namespace nimbus {
namespace {

// A lopsided plume rising along +y in index space (what a Y-up package would store).
float plume(int i, int j, int k) {
  const double r2 = (i - 1) * (i - 1) / 20.0 + (j - 5) * (j - 5) / 45.0 + (k + 1) * (k + 1) / 14.0;
  const double v = (1.0 - r2) * (1.0 + 0.5 * std::sin(0.7 * i + 0.3 * j - 0.4 * k));
  return float(std::max(0.0, v));
}

// Writes a FogVolume float grid (voxel size h, index (0, 0, 0) at the world origin) as .nvdb.
void write_grid(const std::filesystem::path& file, const std::function<float(int, int, int)>& f,
                const nanovdb::CoordBBox& box, double h) {
  nanovdb::GridBuilder<float> builder(0.0f, nanovdb::GridClass::FogVolume);
  builder([&](const nanovdb::Coord& c) { return f(c[0], c[1], c[2]); }, box);
  nanovdb::io::writeGrid(file.string(), builder.getHandle<>(h, nanovdb::Vec3d(0.0), "density"));
}

// The plume stored Y-up (A) and the same voxels turned by a quarter turn about x (B: +y of A is +z of
// B): B(i, j, k) = A(i, k, -j).
struct PlumeFiles {
  test::ScratchDir dir{"xform_plume"};
  std::string y_up = (dir / "y_up.nvdb").string(), z_up = (dir / "z_up.nvdb").string();
  PlumeFiles() {
    write_grid(y_up, plume, {{-6, -2, -6}, {6, 12, 6}}, 0.1);
    write_grid(
        z_up, [](int i, int j, int k) { return plume(i, k, -j); }, {{-6, -6, -2}, {6, 6, 12}}, 0.1);
  }
};

std::string plume_scene(const std::string& file, const std::string& translate, const std::string& transform) {
  return "{" + test::camera_json(8, 8, 30, 6) + R"(, "media": [{"shape": {"type": "vdb", "file": ")" + file +
         R"(", "scale": 2, "translate": )" + translate + "}" + transform + R"(,
      "sigma_s": 4, "sigma_a": 0.2, "phase": {"type": "hg", "g": 0.6}}],
    "lights": [{"type": "directional", "direction": [-0.5, 0.6, -0.62], "irradiance": 3.0},
               {"type": "environment", "radiance": [0.1, 0.15, 0.3]}]})";
}

TEST(TransformMedia, AVdbTurnedAboutXIsTheVolumeStoredYUp) {
  const PlumeFiles files;
  // Y-up file: its own scale and translate first, then the quarter turn, then a translation. The Z-up
  // file places the same voxels with translate = R (0.1, 0.2, 0.3) + (0.1, 0, 0).
  const Scene a = test::scene_from_json(plume_scene(
      files.y_up, "[0.1, 0.2, 0.3]",
      R"(, "transform": {"rotate": [{"axis": [1, 0, 0], "degrees": 90}], "translate": [0.1, 0, 0]})"));
  const Scene b = test::scene_from_json(plume_scene(files.z_up, "[0.2, -0.3, 0.2]", ""));
  const SceneMedia ma(a.media), mb(b.media);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(ma.bounds().lo[k], mb.bounds().lo[k], 1e-12);
    EXPECT_NEAR(ma.bounds().hi[k], mb.bounds().hi[k], 1e-12);
  }
  // Density at random points of (a little more than) the bounds.
  std::mt19937_64 rng(5);
  const Vec3 lo = mb.bounds().lo - Vec3(0.2), hi = mb.bounds().hi + Vec3(0.2);
  int inside = 0;
  for (int n = 0; n < 4000; ++n) {
    Vec3 p;
    for (int c = 0; c < 3; ++c) p[c] = std::uniform_real_distribution<double>(lo[c], hi[c])(rng);
    const double da = ma.density(0, p), db = mb.density(0, p);
    ASSERT_NEAR(da, db, 1e-9) << p;
    inside += db > 0.05;
  }
  EXPECT_GT(inside, 400);  // the comparison saw the volume, not only empty space
  // Pixels, with one global majorant (the same in both: the brick maxima differ in layout, their
  // maximum does not), so both scenes make the same random decisions at the same points: equal up to
  // rounding. Path traced and single scattered.
  const SceneContext ca(a, 0, true), cb(b, 0, true);
  EXPECT_EQ(ca.majorants.cell_majorant(0, 0, 0), cb.majorants.cell_majorant(0, 0, 0));
  const PathTracer pa(ca, 0), pb(cb, 0);
  const SingleScatter sa(ca, SingleSettings{}), sb(cb, SingleSettings{});
  double total = 0.0;
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x)
      for (int s = 0; s < 8; ++s) {
        const Ray ray = ca.camera.generate_ray(x + 0.5, y + 0.5);
        for (const auto& [ia, ib] : {std::pair<const Integrator*, const Integrator*>{&pa, &pb}, {&sa, &sb}}) {
          Rng ra = Rng::for_sample(3, x, y, s), rb = Rng::for_sample(3, x, y, s);
          const Rgb la = ia->Li(ray, ra), lb = ib->Li(ray, rb);
          for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(la[c], lb[c], 1e-7 * (1.0 + std::abs(lb[c]))) << x << " " << y;
          total += average(la);
        }
      }
  EXPECT_GT(total, 0.0);
}

TEST(TransformMedia, AVdbScaleDefaultsToOne) {
  const PlumeFiles files;
  const Scene s = test::scene_from_json("{" + test::camera_json() + R"(, "lights": [], "media": [
      {"shape": {"type": "vdb", "file": ")" +
                                        files.y_up + R"("}, "sigma_s": 1}]})");
  const auto& v = std::get<VdbShape>(s.media[0].shape);
  EXPECT_EQ(v.scale, 1.0);
  const Bounds b = SceneMedia(s.media).bounds(0), g = v.data->world_bounds();
  EXPECT_EQ(b.lo, g.lo);
  EXPECT_EQ(b.hi, g.hi);
}

// ---- Rotation invariance ------------------------------------------------------------------------

// v turned by `deg` degrees about `axis` (Rodrigues, written here independently of Transform).
Vec3 turn(const Vec3& v, const Vec3& axis, double deg) {
  const Vec3 a = normalize(axis);
  const double t = deg * kPi / 180.0;
  return v * std::cos(t) + cross(a, v) * std::sin(t) + a * (dot(a, v) * (1.0 - std::cos(t)));
}

std::string vec(const Vec3& v) { return fmt::format("[{:.17g}, {:.17g}, {:.17g}]", v.x, v.y, v.z); }

// The plume and a box, each rotated with a non-uniform scale, under a sun and a sky; the whole scene
// (media, camera, sun) moved by the rigid map x -> R x + t when `moved`. The camera of the unmoved
// scene is kept when `keep_camera` (the negative control).
Scene rigid_scene(const std::string& file, bool moved, bool keep_camera) {
  const Vec3 axis(1, -2, 0.5), t(0.5, -0.25, 1.0);
  const double deg = moved ? 50.0 : 0.0;
  auto point = [&](const Vec3& p) { return moved ? turn(p, axis, deg) + t : p; };
  auto direction = [&](const Vec3& d) { return moved ? turn(d, axis, deg) : d; };
  const std::string extra =
      moved ? fmt::format(R"(, {{"axis": {}, "degrees": {}}}], "translate": {})", vec(axis), deg, vec(t))
            : "]";
  const Vec3 eye(0.3, -4.0, 0.8), target(0, 0, 0.2), up(0, 0, 1);
  const Vec3 e = keep_camera ? eye : point(eye), l = keep_camera ? target : point(target);
  const Vec3 u = keep_camera ? up : direction(up);
  return test::scene_from_json(fmt::format(
      R"({{"camera": {{"position": {}, "look_at": {}, "up": {}, "fov_y_deg": 28, "width": 10, "height": 10}},
    "media": [{{"shape": {{"type": "vdb", "file": "{}"}}, "sigma_s": 6, "sigma_a": 0.3,
                "phase": {{"type": "hg", "g": 0.5}},
                "transform": {{"scale": [1.5, 0.8, 1.2], "rotate": [{{"axis": [1, 0, 0], "degrees": 20}}{}}}}},
              {{"shape": {{"type": "box", "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]}}, "sigma_s": 1.5,
                "transform": {{"scale": [1.6, 0.3, 0.6], "rotate": [{{"axis": [0, 1, 1], "degrees": 30}}{}}}}}],
    "lights": [{{"type": "directional", "direction": {}, "irradiance": 3.0}},
               {{"type": "environment", "radiance": [0.1, 0.15, 0.3]}}]}})",
      vec(e), vec(l), vec(u), file, extra, extra, vec(direction(Vec3(-0.5, 0.6, -0.62)))));
}

// Every integrator renders the moved scene: finite, non-negative and lit (mfs and octave reach the media
// through the same SceneMedia and majorant grid as pathtrace).
TEST(TransformMedia, EveryIntegratorRendersATransformedScene) {
  const PlumeFiles files;
  Scene scene = rigid_scene(files.y_up, true, false);
  scene.camera.width = scene.camera.height = 6;
  for (const std::string& name : integrator_names()) {
    RenderOptions options;
    options.integrator = name;
    options.spp = 2;
    options.threads = 2;
    const RenderResult r = render(scene, options);
    EXPECT_EQ(r.nonfinite_samples, 0) << name;
    double sum = 0.0;
    for (float v : r.image.rgb) {
      ASSERT_TRUE(std::isfinite(v)) << name;
      ASSERT_GE(v, 0.0f) << name;
      sum += v;
    }
    EXPECT_GT(sum, 0.0) << name;
  }
}

struct PixelStats {
  std::vector<test::MeanAccumulator> px;
};

PixelStats pixel_stats(const Scene& scene, uint64_t seed, int spp) {
  const SceneContext ctx(scene);
  const PathTracer pt(ctx, 0);
  PixelStats out;
  out.px.resize(size_t(scene.camera.width) * scene.camera.height);
  for (int y = 0; y < scene.camera.height; ++y)
    for (int x = 0; x < scene.camera.width; ++x)
      for (int s = 0; s < spp; ++s) {
        Rng rng = Rng::for_sample(seed, x, y, s);
        const double u = (s + 0.5) / spp;  // stratified in x: the same positions in both renders
        const Ray ray = ctx.camera.generate_ray(x + u, y + 0.5);
        out.px[size_t(y) * scene.camera.width + x].add(luminance(pt.Li(ray, rng)));
      }
  return out;
}

// Sum over pixels of z^2 = (mean_a - mean_b)^2 / (se_a^2 + se_b^2): chi-square with one degree of
// freedom per pixel if both renders estimate the same image. Returns the p-value.
double same_image_p_value(const PixelStats& a, const PixelStats& b, double* chi2_out) {
  double chi2 = 0.0;
  int dof = 0;
  for (size_t i = 0; i < a.px.size(); ++i) {
    const double var =
        a.px[i].stderr_mean() * a.px[i].stderr_mean() + b.px[i].stderr_mean() * b.px[i].stderr_mean();
    const double d = a.px[i].mean - b.px[i].mean;
    if (var <= 0.0) {  // both deterministic (the sky alone): must agree to rounding
      EXPECT_NEAR(d, 0.0, 1e-9) << "pixel " << i;
      continue;
    }
    chi2 += d * d / var;
    ++dof;
  }
  *chi2_out = chi2;
  return dof == 0 ? 1.0 : test::gamma_q(0.5 * dof, 0.5 * chi2);
}

TEST(TransformMedia, ARigidlyMovedSceneRendersTheSameImage) {
  const PlumeFiles files;
  const int spp = 128;
  const PixelStats base = pixel_stats(rigid_scene(files.y_up, false, false), 11, spp);
  const PixelStats moved = pixel_stats(rigid_scene(files.y_up, true, false), 12, spp);
  double chi2 = 0.0;
  const double p = same_image_p_value(base, moved, &chi2);
  EXPECT_GT(p, 1e-4) << "chi2 " << chi2 << " over " << base.px.size() << " pixels";
  double mean = 0.0;
  for (const auto& m : base.px) mean += m.mean;
  EXPECT_GT(mean, 0.0);
  // Negative control: the media moved but not the camera is a different image, and the test says so.
  const PixelStats wrong = pixel_stats(rigid_scene(files.y_up, true, true), 12, spp);
  EXPECT_LT(same_image_p_value(base, wrong, &chi2), 1e-6) << "chi2 " << chi2;
}

// ---- Shapes and majorants ------------------------------------------------------------------------

TEST(TransformMedia, ASphereBecomesTheHandComputedEllipsoid) {
  const Scene s = test::scene_from_json("{" + test::camera_json() + R"(, "lights": [], "media": [
      {"shape": {"type": "sphere", "center": [0.2, 0, -0.1], "radius": 0.7}, "sigma_s": 1,
       "transform": {"scale": [2, 1, 0.5], "rotate": [{"axis": [0, 0, 1], "degrees": 30}], "translate": [1, 2, 3]}}]})");
  const SceneMedia media(s.media);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1.8, 1.8);
  int inside = 0;
  for (int n = 0; n < 20000; ++n) {
    const Vec3 p = Vec3(1, 2, 3) + Vec3(u(rng), u(rng), u(rng));
    // By hand: undo the translation, the rotation, the scale; then the sphere test.
    const Vec3 r = turn(p - Vec3(1, 2, 3), Vec3(0, 0, 1), -30);
    const Vec3 q(r.x / 2, r.y, r.z / 0.5);
    const bool in = (q - Vec3(0.2, 0, -0.1)).length() <= 0.7;
    ASSERT_EQ(media.density(0, p), in ? 1.0 : 0.0) << p;
    if (in) ASSERT_TRUE(media.bounds(0).contains(p)) << p;
    inside += in;
  }
  EXPECT_GT(inside, 500);
  // The bounds are the ellipsoid's exact box: half-extent 0.7 |row of M| along each axis.
  const double c30 = std::cos(kPi / 6), s30 = std::sin(kPi / 6);
  EXPECT_NEAR(media.bounds(0).hi.x - media.bounds(0).lo.x, 1.4 * std::hypot(2 * c30, s30), 1e-12);
  EXPECT_NEAR(media.bounds(0).hi.y - media.bounds(0).lo.y, 1.4 * std::hypot(2 * s30, c30), 1e-12);
  EXPECT_NEAR(media.bounds(0).hi.z - media.bounds(0).lo.z, 1.4 * 0.5, 1e-12);
}

TEST(TransformMedia, MaxDensityIsConservativeUnderRotationAndNonUniformScale) {
  const PlumeFiles files;
  const std::string xform =
      R"("transform": {"scale": [1.7, 0.6, 1.1], "rotate": [{"axis": [1, 2, 3], "degrees": 37},
                       {"axis": [0, 1, 0], "degrees": -64}], "translate": [0.3, -0.2, 0.1]})";
  const Scene s = test::scene_from_json("{" + test::camera_json() + R"(, "lights": [], "media": [
      {"shape": {"type": "vdb", "file": ")" +
                                        files.y_up + R"(", "scale": 1.3}, "sigma_s": 1, )" + xform + R"(},
      {"shape": {"type": "cloud", "radius": 0.8, "resolution": 24}, "sigma_s": 2, )" +
                                        xform + R"(},
      {"shape": {"type": "sphere", "radius": 0.6}, "sigma_s": 3, )" +
                                        xform + R"(},
      {"shape": {"type": "box", "min": [-0.4, -0.3, -0.2], "max": [0.4, 0.3, 0.2]}, "sigma_s": 4, )" +
                                        xform + "}]}");
  const SceneMedia media(s.media);
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  for (int i = 0; i < media.count(); ++i) {
    // Boxes of random size and aspect in and around the medium's world bounds.
    const Bounds& mb = media.bounds(i);
    const Vec3 extent = mb.hi - mb.lo;
    int positive = 0;
    for (int n = 0; n < 400; ++n) {
      Bounds box;
      const double size = 0.02 + 0.3 * u01(rng);
      for (int c = 0; c < 3; ++c) {
        box.lo[c] = mb.lo[c] + (u01(rng) * 1.2 - 0.2) * extent[c];
        box.hi[c] = box.lo[c] + size * extent[c] * (0.3 + u01(rng));
      }
      const double bound = media.max_density(i, box);
      for (int k = 0; k < 40; ++k) {
        Vec3 p;
        for (int c = 0; c < 3; ++c) p[c] = box.lo[c] + u01(rng) * (box.hi[c] - box.lo[c]);
        const double d = media.density(i, p);
        ASSERT_LE(d, bound) << "medium " << i << " at " << p;
        positive += d > 0.0;
      }
    }
    EXPECT_GT(positive, 100) << "medium " << i;  // the boxes met the volume
  }
  // The majorant grid over them: never below the extinction at random points of its cells.
  const MajorantGrid grid(media);
  const auto res = grid.resolution();
  const Vec3 cell = (grid.bounds().hi - grid.bounds().lo) / Vec3(res[0], res[1], res[2]);
  for (int n = 0; n < 20000; ++n) {
    Vec3 p;
    for (int c = 0; c < 3; ++c)
      p[c] = grid.bounds().lo[c] + u01(rng) * (grid.bounds().hi[c] - grid.bounds().lo[c]);
    int ijk[3];
    for (int c = 0; c < 3; ++c)
      ijk[c] = std::clamp(int((p[c] - grid.bounds().lo[c]) / cell[c]), 0, res[c] - 1);
    ASSERT_LE(max_component(media.sigma_t(p)), grid.cell_majorant(ijk[0], ijk[1], ijk[2])) << p;
  }
}

}  // namespace
}  // namespace nimbus
