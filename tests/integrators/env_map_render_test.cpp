// The environment image in the integrators and the scene parser: the MIS estimates at a medium point and
// on a surface against quadratures (the surface lit from the direction the image's bright block looks
// along; tests/integrators/env_map_slowtest.cpp: a constant image equals the constant environment), and bad images or fields are errors naming the file and the field.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>

#include "core/sh.h"
#include "integrators/env_light.h"
#include "integrators/mfs.h"
#include "integrators/registry.h"
#include "integrators/surface_light.h"
#include "io/scene_environment.h"
#include "nimbus/error.h"
#include "nimbus/image.h"
#include "support/scenes.h"
#include "support/scratch_dir.h"
#include "support/stats.h"

namespace nimbus {
namespace {

// Writes a w x h float EXR with pixel (i, j) = f(i, j).
template <typename F>
std::string write_map(const test::ScratchDir& dir, const std::string& name, int w, int h, F&& f) {
  Image img(w, h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const Rgb c = f(i, j);
      for (int k = 0; k < 3; ++k) img.pixel(i, j)[k] = float(c[k]);
    }
  const std::string path = (dir / name).string();
  write_exr(path, img);
  return path;
}

TEST(EnvMapRender, MediumPointMatchesQuadrature) {
  // One medium point under a map with a bright block and a dim gradient, HG g = 0.8 towards the block's
  // side: the MIS estimate (unit transmittance) against int L(w) p(d . w) dw by 4 x 4 points per pixel.
  const int W = 48, H = 24;
  auto pixel = [](int i, int j) {
    return i >= 20 && i < 23 && j >= 9 && j < 12 ? Rgb(40.0, 30.0, 20.0) : Rgb(0.1 + 0.01 * j);
  };
  const test::ScratchDir dir("envmap");
  const std::string file = write_map(dir, "block.exr", W, H, pixel);
  const Scene scene = test::scene_from_json("{" + test::camera_json() +
                                            fmt::format(R"(, "media": [],
    "lights": [{{"type": "environment", "file": "{}"}}]}})",
                                                        file));
  const SceneContext ctx(scene);
  const Phase phase = HgPhase{0.8};
  const Vec3 d = normalize(Vec3(-1, 0.3, 0.2));  // travelling away from +x: the block is behind (back-lit)
  for (const Vec3& dir_travel : {d, -d}) {
    Rgb exact(0.0);
    for (int j = 0; j < 4 * H; ++j)
      for (int i = 0; i < 4 * W; ++i) {
        const double solid =
            2.0 * kPi / (4.0 * W) * (std::cos(kPi * j / (4.0 * H)) - std::cos(kPi * (j + 1) / (4.0 * H)));
        const Vec3 w = latlong_to_direction((i + 0.5) / (4.0 * W), (j + 0.5) / (4.0 * H));
        exact += pixel(i / 4, j / 4) * (phase_eval(phase, dot(dir_travel, w)) * solid);
      }
    test::MeanAccumulator m;
    for (int k = 0; k < 20000; ++k) {
      Rng rng(4, k);
      m.add(
          medium_env_map_light(*ctx.env_map, phase, dir_travel, rng, [](const Vec3&) { return Rgb(1.0); }).x);
    }
    EXPECT_NEAR(m.mean, exact.x, 5 * m.stderr_mean() + 2e-3 * exact.x);
    EXPECT_LT(m.stderr_mean(), 0.02 * exact.x);
  }
}

TEST(EnvMapRender, SurfaceLitFromTheBrightBlockDirection) {
  // A bright block at the image's centre (+x): a surface facing +x is lit by int L cos / pi dw, one facing
  // -x not at all. Exact value: the block's radiance times the cosine-weighted solid angle of its pixels.
  const test::ScratchDir dir("envmap");
  const int W = 64, H = 32;
  auto in_block = [](int i, int j) { return i >= 30 && i < 34 && j >= 14 && j < 18; };
  const std::string file =
      write_map(dir, "block.exr", W, H, [&](int i, int j) { return in_block(i, j) ? Rgb(50.0) : Rgb(0.0); });
  const Scene scene = test::scene_from_json("{" + test::camera_json() +
                                            fmt::format(R"(, "media": [],
    "lights": [{{"type": "environment", "file": "{}", "intensity": 2}}]}})",
                                                        file));
  const SceneContext ctx(scene);
  double exact = 0.0;  // int L max(0, w . x) / pi dw by 8 x 8 points per pixel
  for (int j = 14 * 8; j < 18 * 8; ++j)
    for (int i = 30 * 8; i < 34 * 8; ++i) {
      const double t = (j + 0.5) / (8.0 * H), phi = kPi * (1.0 - 2.0 * (i + 0.5) / (8.0 * W));
      const double solid =
          2.0 * kPi / (8.0 * W) * (std::cos(kPi * j / (8.0 * H)) - std::cos(kPi * (j + 1) / (8.0 * H)));
      exact += 100.0 * std::max(0.0, std::sin(kPi * t) * std::cos(phi)) / kPi * solid;
    }
  for (double facing : {1.0, -1.0}) {
    SurfaceHit hit;
    hit.p = Vec3(0.0);
    hit.ns = hit.ng = Vec3(facing, 0, 0);
    test::MeanAccumulator m;
    for (int k = 0; k < 4000; ++k) {
      Rng rng(9, k);
      m.add(surface_env_map_light(ctx, hit, rng).x);
    }
    if (facing > 0) {
      EXPECT_NEAR(m.mean, exact, 5 * m.stderr_mean() + 1e-9);
      EXPECT_LT(m.stderr_mean(), 0.02 * exact);
    } else {
      EXPECT_EQ(m.mean, 0.0);
    }
  }
}

TEST(EnvMapRender, RealSkyMisBeatsPhaseSampling) {
  // The CC0 sunrise sky (data/environment/): at a point of an HG g = 0.85 medium, the MIS estimate of
  // int Y(L(w)) p(d . w) dw against a quadrature over the pixels (2 x 2 points each), and its variance
  // against plain phase sampling (the constant environment's method; heavy-tailed here, as the sun is
  // small and bright: its sample mean is not compared).
  const Image img =
      read_environment_image(std::string(NIMBUS_SOURCE_DIR) + "/data/environment/sunrise_1k.exr");
  ASSERT_EQ(img.width, 1024);
  const EnvMap map(img.width, img.height, img.rgb, Transform(), 1.0);
  const Phase phase = HgPhase{0.85};
  const int W = img.width, H = img.height, S = 2;
  for (const Vec3& d : {normalize(Vec3(-0.8, 0.6, -0.1)), normalize(Vec3(0.0, 1.0, -0.3))}) {
    double exact = 0.0;
    for (int j = 0; j < H * S; ++j) {
      const double solid =
          2.0 * kPi / (S * W) * (std::cos(kPi * j / (S * H)) - std::cos(kPi * (j + 1) / (S * H)));
      for (int i = 0; i < W * S; ++i) {
        const Vec3 w = latlong_to_direction((i + 0.5) / (S * W), (j + 0.5) / (S * H));
        exact += luminance(map.pixel(i / S, j / S)) * phase_eval(phase, dot(d, w)) * solid;
      }
    }
    test::MeanAccumulator mis, plain;
    for (int k = 0; k < 40000; ++k) {
      Rng r1(6, k), r2(7, k);
      mis.add(luminance(medium_env_map_light(map, phase, d, r1, [](const Vec3&) { return Rgb(1.0); })));
      const double u1 = r2.uniform(), u2 = r2.uniform();
      plain.add(luminance(map.eval(phase_sample(phase, d, u1, u2))));
    }
    EXPECT_NEAR(mis.mean, exact, 5 * mis.stderr_mean() + 2e-3 * exact);
    EXPECT_LT(mis.stderr_mean(), 0.01 * exact);
    EXPECT_LT(mis.variance(), 0.5 * plain.variance());
    std::printf("sunrise sky, HG 0.85: exact %.4g, MIS %.4g, variance MIS %.4g, phase sampling %.4g\n", exact,
                mis.mean, mis.variance(), plain.variance());
  }
}

TEST(EnvMapRender, ScatterGridLeavesTheImagesFirstScatterToTheMarch) {
  // mfs takes an environment image's first wide scatter on the camera march (as a light's), so its
  // scatter grid carries the image's photons only after their first wide scatter: in a nearly empty box
  // (sigma_s 1e-9) the grid at the centre holds nothing of the image. With a constant environment it
  // still holds the sky's unscattered light (order 0): the image's moments M_00 Y_00 there.
  const test::ScratchDir dir("envmap");
  const int W = 64, H = 32;
  const std::string file = write_map(dir, "tilt.exr", W, H, [&](int, int j) {
    return Rgb(1.0 + 0.6 * std::cos(kPi * (j + 0.5) / H), 1.0, 1.0);
  });
  std::array<Rgb, kShMaxBands> chi;
  chi.fill(Rgb(1.0));
  for (const bool image : {true, false}) {
    const std::string light = image ? fmt::format(R"({{"type": "environment", "file": "{}"}})", file)
                                    : std::string(R"({"type": "environment", "radiance": 1.0})");
    const Scene scene = test::scene_from_json("{" + test::camera_json() + R"(,
    "media": [{"shape": {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1]}, "sigma_s": 1e-9}],
    "lights": [)" + light + R"(],
    "integrator": {"type": "mfs", "photons": 131072, "scatter_grid_resolution": 4}})");
    const SceneContext ctx(scene);
    const auto mfs = make_integrator(ctx, scene.integrator);
    const ScatterGrid* grid = dynamic_cast<const MfsIntegrator&>(*mfs).scatter_grid();
    ASSERT_NE(grid, nullptr);
    const double got = grid->scattered(Vec3(0.01, -0.02, 0.03), Vec3(0, 0, 1), chi).x;
    if (image)
      EXPECT_LT(std::abs(got), 1e-6) << "the image's unscattered light is in the grid";
    else
      EXPECT_NEAR(got, 1.0, 0.05);  // the constant sky's radiance, 1, from the grid's photons
  }
}

std::string env_parse_error(const nlohmann::json& doc) {
  try {
    parse_scene(doc, "scene.json", ".");
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(EnvMapParse, BadInputsNameTheFileAndField) {
  const test::ScratchDir dir("envmap");
  const std::string good = write_map(dir, "sky.exr", 8, 4, [](int, int) { return Rgb(1.0); });
  // A PNG and an EXR of integer channels are not HDR.
  const std::string png = (dir / "sky.png").string();
  write_png(png, Image(8, 4));
  const std::string uint_exr = (dir / "uint.exr").string();
  {
    Imf::Header header(4, 2);
    for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::UINT));
    std::vector<unsigned> px(8 * 3, 1u);
    Imf::OutputFile out(uint_exr.c_str(), header);
    Imf::FrameBuffer fb;
    for (int c = 0; c < 3; ++c)
      fb.insert(c == 0   ? "R"
                : c == 1 ? "G"
                         : "B",
                Imf::Slice(Imf::UINT, reinterpret_cast<char*>(px.data() + c), 3 * sizeof(unsigned),
                           12 * sizeof(unsigned)));
    out.setFrameBuffer(fb);
    out.writePixels(2);
  }
  auto scene = [](const nlohmann::json& light) {
    nlohmann::json doc = nlohmann::json::parse("{" + test::camera_json() + R"(, "media": []})");
    doc["lights"] = nlohmann::json::array({light});  // not {light}: clang takes that for a copy
    return doc;
  };
  struct Case {
    nlohmann::json light;
    std::string needle;
  };
  const std::vector<Case> cases = {
      {{{"type", "environment"}, {"file", (dir / "missing.exr").string()}}, "/lights/0/file"},
      {{{"type", "environment"}, {"file", png}}, "not an OpenEXR file"},
      {{{"type", "environment"}, {"file", uint_exr}}, "integers"},
      {{{"type", "environment"}, {"file", good}, {"radiance", 1.0}}, "/lights/0/radiance"},
      {{{"type", "environment"}, {"file", good}, {"transform", {{"scale", 2.0}}}},
       "/lights/0/transform/scale"},
      {{{"type", "environment"}, {"file", good}, {"transform", {{"translate", {1, 0, 0}}}}},
       "/lights/0/transform/translate"},
      {{{"type", "environment"}, {"radiance", 1.0}, {"intensity", 2.0}}, "/lights/0/intensity"},
      {{{"type", "environment"}, {"file", good}, {"intensity", -1.0}}, "/lights/0/intensity"},
      {{{"type", "environment"}, {"file", good}, {"exposure", 1.0}}, "exposure"},
  };
  for (const Case& c : cases) {
    const std::string msg = env_parse_error(scene(c.light));
    EXPECT_NE(msg.find("scene.json"), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.needle), std::string::npos) << msg;
  }
  EXPECT_NE(env_parse_error(scene({{"type", "environment"}, {"file", png}})).find("/lights/0/file"),
            std::string::npos);
  // Two images in one scene.
  nlohmann::json two = scene({{"type", "environment"}, {"file", good}});
  two["lights"].push_back({{"type", "environment"}, {"file", good}});
  EXPECT_NE(env_parse_error(two).find("/lights/1/file"), std::string::npos);
  // Rotations are fine, and a relative path resolves against the scene's folder.
  const Scene ok = parse_scene(scene({{"type", "environment"},
                                      {"file", "sky.exr"},
                                      {"transform", {{"rotate", {{{"axis", {0, 0, 1}}, {"degrees", 30}}}}}}}),
                               "scene.json", dir.path);
  EXPECT_TRUE(std::get<EnvironmentLight>(ok.lights[0]).map != nullptr);
}

}  // namespace
}  // namespace nimbus
