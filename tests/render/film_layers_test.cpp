// The compositing layers (docs/compositing.md) against analytic media: the alpha of a homogeneous
// sphere (1 - exp(-sigma_t chord)), the depth where a slab's transmittance is 1/2, the albedo there, a
// transparent film, and the film's EXR channels.
#include "render/film_layers.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "integrators/camera_layers.h"
#include "integrators/registry.h"
#include "nimbus/error.h"
#include "nimbus/render.h"
#include "support/scenes.h"
#include "support/stats.h"

namespace nimbus {
namespace {

const char* kIntegrators[] = {"pathtrace", "single", "octave", "mfs"};

// Each integrator's settings for exact-as-possible layers: fine marches (the march's boundary steps are
// its only error in a homogeneous medium: at most tau_step of optical depth per boundary), few photons.
nlohmann::json fine_options(const std::string& type) {
  if (type == "single" || type == "octave") return {{"tau_step", 0.001}};
  if (type == "mfs") return {{"tau_step", 0.001}, {"photons", 2000}, {"beam_photons", 0}};
  return nlohmann::json::object();
}

std::string layers_sphere_scene(double sigma_s, double sigma_a, const std::string& lights) {
  return "{" + test::camera_json(8, 8) + R"(, "media": [{"shape": {"type": "sphere", "center": [0, 0, 0],
    "radius": 1}, "sigma_s": )" +
         std::to_string(sigma_s) + R"(, "sigma_a": )" + std::to_string(sigma_a) +
         R"(, "phase": {"type": "isotropic"}}], "lights": [)" + lights + "]}";
}

const std::string kSun = R"({"type": "directional", "direction": [1, 1, -1], "irradiance": 2.0})";
const std::string kSky = R"({"type": "environment", "radiance": [0.1, 0.2, 0.4]})";

// The mean of `n` samples of alpha (no environment: 1 - mean escape transmittance) for one ray.
test::MeanAccumulator alpha_of(const Integrator& integrator, const Ray& ray, int n) {
  test::MeanAccumulator a;
  for (int i = 0; i < n; ++i) {
    Rng rng(11, uint64_t(i));
    CameraSample s;
    integrator.Li(ray, rng, &s);
    a.add(sample_alpha(s, false));
  }
  return a;
}

TEST(FilmLayers, AlphaOfAHomogeneousSphereIsOneMinusItsTransmittance) {
  const double sigma_s = 1.2, sigma_a = 0.3, sigma_t = sigma_s + sigma_a;
  const Scene scene = test::scene_from_json(layers_sphere_scene(sigma_s, sigma_a, kSun));
  const SceneContext ctx(scene);
  const Vec3 o(0, -5, 0);
  for (const char* type : kIntegrators) {
    IntegratorSettings settings;
    settings.type = type;
    settings.options = fine_options(type);
    const auto integrator = make_integrator(ctx, settings);
    for (const double b : {0.0, 0.5, 0.9}) {  // impact parameter: chord 2 sqrt(1 - b^2)
      const Ray ray{o, normalize(Vec3(0, 5, b))};
      const double h = 5.0 * b / std::sqrt(25.0 + b * b);  // the ray's distance from the centre
      const double expected = 1.0 - std::exp(-sigma_t * 2.0 * std::sqrt(1.0 - h * h));
      const int n = std::string(type) == "pathtrace" ? 20000 : 20;
      const test::MeanAccumulator a = alpha_of(*integrator, ray, n);
      // pathtrace: a Bernoulli escape indicator, standard error sqrt(p (1 - p) / n) <= 0.0036 (5 of
      // them); the marches: at most 2 tau_step of optical depth at the boundaries.
      const double tol = std::string(type) == "pathtrace" ? 5.0 * std::max(a.stderr_mean(), 1e-3) : 2.5e-3;
      EXPECT_NEAR(a.mean, expected, tol) << type << " b " << b;
    }
  }
}

TEST(FilmLayers, DepthWhereASlabsTransmittanceIsOneHalf) {
  // A box slab entered at t = 4 along the camera ray: T = exp(-sigma_t (t - 4)) = 1/2 at 4 + ln 2 / sigma_t.
  const Scene scene = test::scene_from_json("{" + test::camera_json(8, 8) + R"(, "media": [{"shape":
    {"type": "box", "min": [-2, -1, -2], "max": [2, 3, 2]}, "sigma_s": [0.8, 1.0, 1.2], "sigma_a": 0.4}],
    "lights": [)" + kSun + "]}");
  const SceneContext ctx(scene);
  const Ray ray{Vec3(0, -5, 0), Vec3(0, 1, 0)};
  const Rgb sigma_t(1.2, 1.4, 1.6);
  // The depth solves mean_c exp(-sigma_c s) = 1/2 (bisection to 1e-12).
  double lo = 0.0, hi = 10.0;
  for (int i = 0; i < 80; ++i) {
    const double s = 0.5 * (lo + hi);
    (average(exp(-sigma_t * s)) > 0.5 ? lo : hi) = s;
  }
  const double expected = 4.0 + lo;
  for (const char* type : kIntegrators) {
    IntegratorSettings settings;
    settings.type = type;
    settings.options = fine_options(type);
    const auto integrator = make_integrator(ctx, settings);
    Rng rng(3, 0);
    CameraSample s;
    integrator->Li(ray, rng, &s);
    // Every step is homogeneous: the crossing's interpolation is exact (up to the majorant grid's
    // bounds, padded by a few 1e-6 of the media's extent).
    EXPECT_NEAR(s.depth, expected, 1e-5) << type;
    EXPECT_NEAR(s.albedo[0], 0.8 / 1.2, 1e-12) << type;
    EXPECT_NEAR(s.albedo[2], 1.2 / 1.6, 1e-12) << type;
    // A ray that misses the media has no depth and no albedo.
    CameraSample miss;
    integrator->Li({Vec3(0, -5, 0), Vec3(0, 0, 1)}, rng, &miss);
    EXPECT_TRUE(std::isinf(miss.depth)) << type;
    EXPECT_EQ(miss.albedo[0], 0.0) << type;
  }
}

TEST(FilmLayers, HalfTransmittanceFractionSolvesTheStep) {
  EXPECT_NEAR(half_transmittance_fraction(Rgb(1.0), Rgb(0.25)), 0.5, 1e-12);
  const Rgb T0(0.9, 0.8, 0.7), T1(0.1, 0.3, 0.4);
  const double u = half_transmittance_fraction(T0, T1);
  Rgb Tu;
  for (int c = 0; c < 3; ++c) Tu[c] = T0[c] * std::pow(T1[c] / T0[c], u);
  EXPECT_NEAR(average(Tu), 0.5, 1e-8);
}

TEST(FilmLayers, DirectIsTheUnscatteredAndSingleScatteredLight) {
  const Scene scene = test::scene_from_json(layers_sphere_scene(1.5, 0.2, kSun + ", " + kSky));
  const SceneContext ctx(scene);
  const Ray ray{Vec3(0, -5, 0), normalize(Vec3(0.1, 5, 0.2))};
  auto make = [&](const std::string& type, nlohmann::json options, int max_events = 0) {
    IntegratorSettings settings;
    settings.type = type;
    settings.max_events = max_events;
    settings.options = std::move(options);
    return make_integrator(ctx, settings);
  };
  // Where an integrator's whole image is direct light, direct is Li: single; pathtrace with one event;
  // octave with one octave (its octave 0 is single scattering); mfs with one wide scatter and no
  // environment (no scatter grid) is tested below.
  const std::pair<std::unique_ptr<Integrator>, std::string> all_direct[] = {
      {make("single", nlohmann::json::object()), "single"},
      {make("pathtrace", nlohmann::json::object(), 1), "pathtrace max_events 1"},
      {make("octave", {{"octaves", 1}}), "octave 1"}};
  for (const auto& [integrator, name] : all_direct) {
    for (int i = 0; i < 20; ++i) {
      Rng rng(7, uint64_t(i));
      CameraSample s;
      const Rgb L = integrator->Li(ray, rng, &s);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.direct[c], L[c], 1e-12 * (1.0 + L[c])) << name;
    }
  }
  // pathtrace's direct (background + first NEE) estimates single's image: the same mean.
  const auto pt = make("pathtrace", nlohmann::json::object());
  const auto single = make("single", {{"tau_step", 0.05}});
  test::MeanAccumulator direct[3], reference[3];
  for (int i = 0; i < 8000; ++i) {
    Rng r1(1, uint64_t(i));
    CameraSample s;
    pt->Li(ray, r1, &s);
    for (int c = 0; c < 3; ++c) direct[c].add(s.direct[c]);
  }
  for (int i = 0; i < 1000; ++i) {
    Rng r2(2, uint64_t(i));
    const Rgb L = single->Li(ray, r2);
    for (int c = 0; c < 3; ++c) reference[c].add(L[c]);
  }
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(
        direct[c].mean, reference[c].mean,
        5 * std::hypot(direct[c].stderr_mean(), reference[c].stderr_mean()) + 0.005 * reference[c].mean)
        << c;
}

TEST(FilmLayers, MfsDirectIsEverythingWithoutTheScatterGrid) {
  const Scene scene = test::scene_from_json(layers_sphere_scene(1.5, 0.2, kSun));
  const SceneContext ctx(scene);
  IntegratorSettings settings;
  settings.type = "mfs";
  settings.options = {{"large_angle_scatters", 1}, {"beam_photons", 0}};
  const auto mfs = make_integrator(ctx, settings);
  Rng rng(3, 1);
  CameraSample s;
  const Rgb L = mfs->Li({Vec3(0, -5, 0), normalize(Vec3(0.1, 5, 0.2))}, rng, &s);
  EXPECT_GT(L[0], 0.0);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.direct[c], L[c], 1e-12);
}

RenderResult render_layers_with(const std::string& text, const std::string& type,
                                const nlohmann::json& film) {
  nlohmann::json doc = nlohmann::json::parse(text);
  doc["integrator"] = {{"type", type}, {"spp", 4}, {"seed", 5}};
  if (!film.is_null()) doc["film"] = film;
  RenderOptions options;
  options.threads = 2;
  return render(parse_scene(doc, "test.json", "."), options);
}

const ImageChannel* channel(const Image& image, const std::string& name) {
  for (const ImageChannel& c : image.channels)
    if (c.name == name) return &c;
  return nullptr;
}

TEST(FilmLayers, TransparentFilmLeavesTheEnvironmentOut) {
  const std::string text = layers_sphere_scene(2.0, 0.2, kSun + ", " + kSky);
  const Rgb sky(0.1, 0.2, 0.4);
  for (const char* type : {"single", "pathtrace"}) {
    const RenderResult opaque = render_layers_with(text, type, nullptr);
    const RenderResult clear =
        render_layers_with(text, type, {{"transparent", true}, {"layers", {"transmittance"}}});
    const ImageChannel* tr[3] = {channel(clear.image, "transmittance.R"),
                                 channel(clear.image, "transmittance.G"),
                                 channel(clear.image, "transmittance.B")};
    ASSERT_TRUE(tr[0] && tr[1] && tr[2]);
    const size_t n = opaque.image.alpha.size();
    ASSERT_EQ(n, 64u);
    for (size_t i = 0; i < n; ++i) {
      // The environment is an opaque background: alpha 1 (no holdouts).
      EXPECT_FLOAT_EQ(opaque.image.alpha[i], 1.0f);
      // The same samples: the difference is the background T_escape x sky, pixel by pixel.
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(opaque.image.rgb[3 * i + c] - clear.image.rgb[3 * i + c], tr[c]->data[i] * sky[c], 1e-6)
            << type << " pixel " << i;
      const double mean_T = (tr[0]->data[i] + tr[1]->data[i] + tr[2]->data[i]) / 3.0;
      EXPECT_NEAR(clear.image.alpha[i], 1.0 - mean_T, 1e-6) << type << " pixel " << i;
    }
    // The corner pixels miss the sphere: transparent and black.
    EXPECT_FLOAT_EQ(clear.image.alpha[0], 0.0f);
    EXPECT_FLOAT_EQ(clear.image.rgb[0], 0.0f);
  }
}

TEST(FilmLayers, LayersBecomeNamedChannels) {
  const std::string text = layers_sphere_scene(2.0, 0.2, kSun + ", " + kSky);
  const RenderResult r = render_layers_with(text, "single", {{"layers", film_layer_names()}});
  std::vector<std::string> names;
  for (const ImageChannel& c : r.image.channels) names.push_back(c.name);
  const std::vector<std::string> expected = {
      "Z",        "transmittance.R", "transmittance.G", "transmittance.B", "direct.R", "direct.G",
      "direct.B", "indirect.R",      "indirect.G",      "indirect.B",      "albedo.R", "albedo.G",
      "albedo.B", "normal.X",        "normal.Y",        "normal.Z",        "samples.X"};
  EXPECT_EQ(names, expected);
  // single is all direct; the samples layer counts; a missed pixel has an infinite depth.
  EXPECT_NEAR(channel(r.image, "indirect.G")->data[27], 0.0, 1e-6);
  EXPECT_EQ(channel(r.image, "samples.X")->data[5], 4.0f);
  EXPECT_TRUE(std::isinf(channel(r.image, "Z")->data[0]));
  const float z = channel(r.image, "Z")->data[27];
  EXPECT_GT(z, 4.0f);
  EXPECT_LT(z, 5.0f);
  // Without layers the image is RGBA only.
  EXPECT_TRUE(render_layers_with(text, "single", nullptr).image.channels.empty());
}

TEST(FilmLayers, UnknownOrRepeatedLayersAreErrors) {
  Film film(2, 2);
  EXPECT_THROW(FilmLayers(film, FilmSettings{false, {"depth", "zdepth"}}, false), Error);
  Film other(2, 2);
  EXPECT_THROW(FilmLayers(other, FilmSettings{false, {"depth", "depth"}}, false), Error);
}

}  // namespace
}  // namespace nimbus
