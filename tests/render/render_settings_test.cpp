// An image says exactly how it was made: the resolved integrator block (overrides applied, "auto"
// choices made) is in the result and the EXR header, and rendering the header's scene again gives the
// same image.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "integrators/mfs_settings.h"
#include "nimbus/render.h"
#include "scene/context.h"
#include "support/scenes.h"
#include "transport/phase_split.h"

namespace nimbus {
namespace {

std::string meta(const RenderResult& r, const std::string& key) {
  for (const auto& [k, v] : r.metadata)
    if (k == key) return v;
  return "";
}

Scene settings_sphere_scene(const std::string& integrator, int width = 8, int height = 6,
                            double sigma_s = 3.0) {
  return test::scene_from_json("{" + test::camera_json(width, height) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": )" +
                               std::to_string(sigma_s) + R"(, "sigma_a": 0.1,
               "phase": {"type": "hg", "g": 0.8}}],
    "lights": [{"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": 1.0},
               {"type": "environment", "radiance": 0.2}],
    "integrator": )" + integrator +
                               "}");
}

TEST(RenderSettings, AutoChoicesAreResolvedInTheHeader) {
  const Scene scene =
      settings_sphere_scene(R"({"type": "mfs", "spp": 1, "photons": 4096, "beam_photons": 1024})");
  const RenderResult r = render(scene);
  ASSERT_TRUE(r.settings["scatter_grid_resolution"].is_number_integer());
  EXPECT_GE(r.settings["scatter_grid_resolution"].get<int>(), 24);
  EXPECT_LE(r.settings["scatter_grid_resolution"].get<int>(), 64);
  EXPECT_EQ(r.settings["type"], "mfs");
  EXPECT_EQ(r.settings["photons"], 4096);
  EXPECT_EQ(meta(r, "nimbus/integrator_settings"), r.settings.dump());
  const nlohmann::json rendered = nlohmann::json::parse(meta(r, "nimbus/scene"));
  EXPECT_EQ(rendered["integrator"], r.settings);

  // The header's scene renders the same image, bit for bit.
  const Scene again = parse_scene(rendered, "header", ".");
  const RenderResult r2 = render(again);
  ASSERT_EQ(r2.image.rgb.size(), r.image.rgb.size());
  EXPECT_EQ(std::memcmp(r2.image.rgb.data(), r.image.rgb.data(), r.image.rgb.size() * sizeof(float)), 0);
  EXPECT_EQ(r2.settings, r.settings);
}

// The "auto" grid resolution: cells of ~1.6 optical depths, 32 to 64 nodes, from 512 x 512 pixels on;
// 7/8 of that up to 128 x 128, 1/32 more per doubling of the width between.
// "auto" edge samples: where the camera looks into a light's forward peak (a backlit medium's silver lining)
// 64 up to 128 x 128 pixels, 64 / sqrt(pixels / 128^2) above, at least 16; 16 elsewhere; a number given stays.
TEST(RenderSettings, AutoEdgeSamplesFollowTheLightsForwardPeak) {
  const auto scene_json = [](const std::string& direction, const std::string& extra, int w, int h) {
    return "{" + test::camera_json(w, h) + R"(,
      "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 3, "sigma_a": 0.1,
                 "phase": {"type": "hg", "g": 0.8}}],
      "lights": [{"type": "directional", "direction": )" +
           direction +
           R"(, "irradiance": 1.0}],
      "integrator": {"type": "mfs", "spp": 1, "photons": 4096, "beam_photons": 1024)" +
           extra + "}}";
  };
  const auto edge = [&](const std::string& direction, const std::string& extra) {
    return render(test::scene_from_json(scene_json(direction, extra, 8, 6))).settings["edge_samples"];
  };
  EXPECT_EQ(edge("[0, -1, 0]", ""), 64);      // backlit: the camera looks into the peak
  EXPECT_EQ(edge("[-1, 0.3, 0.2]", ""), 16);  // side-lit
  EXPECT_EQ(edge("[0, 1, 0]", ""), 16);       // front-lit
  EXPECT_EQ(edge("[0, -1, 0]", R"(, "edge_samples": 4)"), 4);
  const auto at_size = [&](int w, int h) {  // the peak's cut angle of HG 0.8 at its "auto" peak fraction
    const SceneContext ctx(test::scene_from_json(scene_json("[0, -1, 0]", "", w, h)));
    return auto_edge_samples(ctx, PhaseSplit(HgPhase{0.8}, 0.64).cut_angle());
  };
  EXPECT_EQ(at_size(128, 128), 64);
  EXPECT_EQ(at_size(256, 256), 32);
  EXPECT_EQ(at_size(512, 512), 16);
  EXPECT_EQ(at_size(1920, 1080), 16);
}

TEST(RenderSettings, AutoGridResolutionFollowsTheImageAndTheOpticalSize) {
  const std::string mfs = R"({"type": "mfs", "spp": 1})";
  struct Case {
    int width, height, thin, thick, thicker;
  };
  // Extinction 3.1, 30.1 and 60.1 over a diameter of 2: 32, 38 (60.2 / 1.6) and 64 (75.1, clamped) nodes
  // from 512 x 512 on.
  for (const Case c :
       {Case{8, 6, 24, 29, 48}, Case{128, 128, 24, 29, 48}, Case{181, 181, 26, 31, 52},
        Case{256, 256, 28, 33, 56}, Case{512, 512, 32, 38, 64}, Case{1920, 1080, 32, 38, 64}}) {
    const auto nodes = [&](double sigma_s) {
      return auto_scatter_grid_resolution(
          SceneContext(settings_sphere_scene(mfs, c.width, c.height, sigma_s)));
    };
    EXPECT_EQ(nodes(3.0), c.thin) << c.width << "x" << c.height;
    EXPECT_EQ(nodes(30.0), c.thick) << c.width << "x" << c.height;
    EXPECT_EQ(nodes(60.0), c.thicker) << c.width << "x" << c.height;
  }
}

// "auto" photons: 2^18 up to 128 x 128 pixels, then 2^18 sqrt(pixels / 128^2), from the whole image's pixels,
// times the factor of the medium's collisions per photon (the same pilot at every image size): a crop of a
// 256 x 256 image traces twice the 8 x 6 image's count, as the whole 256 x 256 image would. A thin sphere's
// factor is the most, 4: 2^20 at 8 x 6 and 2^21 for the crop (a rule taking the larger of the two factors
// instead of their product would stay at 2^20).
TEST(RenderSettings, AutoPhotonsFollowTheWholeImagesPixels) {
  const std::string mfs = R"({"type": "mfs", "spp": 1, "beam_photons": 1024, "scatter_grid_resolution": 8})";
  RenderOptions o;
  o.region = Region{100, 100, 102, 101};
  for (const double sigma_s : {3.0, 0.3}) {
    const int small = render(settings_sphere_scene(mfs, 8, 6, sigma_s)).settings["photons"];
    EXPECT_GE(small, 1 << 18);
    EXPECT_LE(small, 1 << 20);
    const int crop = render(settings_sphere_scene(mfs, 256, 256, sigma_s), o).settings["photons"];
    EXPECT_NEAR(crop, 2.0 * small, 1.0) << sigma_s;
    if (sigma_s < 1.0) EXPECT_EQ(crop, 1 << 21);
  }
}

// "auto" photons by the pilot's collisions per photon C, 2^18 clamp(sqrt(3.4 / C), 1/2, 4): an optically
// thick sphere (radius 10 optical depths, albedo 0.99; ~4.4 collisions per photon) takes a little less than
// 2^18, a very thick one (radius 60, ~20 collisions) half, a thin one (0.4 optical depths) more, at most 4 x
// 2^18; a count given is kept.
TEST(RenderSettings, AutoPhotonsFollowTheMediumsCollisions) {
  const std::string mfs = R"({"type": "mfs", "spp": 1, "beam_photons": 1024, "scatter_grid_resolution": 8})";
  const int thick = render(settings_sphere_scene(mfs, 4, 3, 9.9)).settings["photons"];
  EXPECT_LT(thick, 1 << 18);
  EXPECT_GT(thick, 1 << 17);
  EXPECT_EQ(render(settings_sphere_scene(mfs, 4, 3, 60.0)).settings["photons"], 1 << 17);
  const int thin = render(settings_sphere_scene(mfs, 4, 3, 0.3)).settings["photons"];
  const int mid = render(settings_sphere_scene(mfs, 4, 3, 3.0)).settings["photons"];
  EXPECT_GT(thin, mid);
  EXPECT_GT(mid, 1 << 18);
  EXPECT_LE(thin, 1 << 20);
  const std::string given = R"({"type": "mfs", "spp": 1, "photons": 5000, "beam_photons": 1024})";
  EXPECT_EQ(render(settings_sphere_scene(given, 4, 3, 0.3)).settings["photons"], 5000);
}

// "auto" photons where the camera looks into a light's forward peak: half. The dense sphere above, lit from
// behind (as in AutoBeamPhotonsFollowThePixelsWhereTheCameraLooksIntoTheForwardPeak), takes half what it
// takes lit from the side (the pilot's collision factor, ~0.87, multiplies both; its collisions differ a
// little with the light's direction).
TEST(RenderSettings, AutoPhotonsHalfWhereTheCameraLooksIntoTheForwardPeak) {
  const auto scene = [](const std::string& direction) {
    return test::scene_from_json("{" + test::camera_json(4, 3) + R"(,
      "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 9.9, "sigma_a": 0.1,
                 "phase": {"type": "hg", "g": 0.8}}],
      "lights": [{"type": "directional", "direction": )" +
                                 direction + R"(, "irradiance": 1.0},
                 {"type": "environment", "radiance": 0.2}],
      "integrator": {"type": "mfs", "spp": 1, "beam_photons": 1024, "scatter_grid_resolution": 8}})");
  };
  const int back = render(scene("[0.3, -1, 0.2]")).settings["photons"];
  const int side = render(scene("[-1, 0.3, 0.2]")).settings["photons"];
  EXPECT_NEAR(double(back) / double(side), 0.5, 0.03);
  EXPECT_GT(side, 1 << 17);
}

// "auto" beam photons in thin media (the scatter grid pilot's collisions per photon below 1.2): 2^15
// sqrt(pixels / 128^2) for every light, seen from the side too. A side-lit sphere of optical radius 0.3
// traces 2^16 in a crop of a 256 x 256 image and 2^15 at 8 x 6; one of radius 10 (~4 collisions per photon)
// 2^14; with the scatter grid's photons given the same 2^16 (the pilot still runs for the beam count: the
// grid's photons given do not change the beam grid). With a spot light beside the sun (which the beam grid
// does not trace) the header holds one count too, and the scene in the header (both counts given: no pilot)
// renders the same image.
TEST(RenderSettings, AutoBeamPhotonsFollowThePixelsInThinMedia) {
  const std::string sun = R"({"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": 1.0})";
  const auto scene = [&](double sigma_s, int size, const std::string& photons, const std::string& lights) {
    return test::scene_from_json("{" + test::camera_json(size, size) + R"(,
      "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": )" +
                                 std::to_string(sigma_s) + R"(, "phase": {"type": "hg", "g": 0.8}}],
      "lights": [)" + lights + R"(],
      "integrator": {"type": "mfs", "spp": 1, "photons": )" +
                                 photons + R"(, "scatter_grid_resolution": 8}})");
  };
  RenderOptions crop;
  crop.region = Region{128, 128, 129, 129};
  EXPECT_EQ(render(scene(0.3, 256, "\"auto\"", sun), crop).settings["beam_photons"], 1 << 16);
  EXPECT_EQ(render(scene(0.3, 8, "\"auto\"", sun)).settings["beam_photons"], 1 << 15);
  EXPECT_EQ(render(scene(10.0, 256, "\"auto\"", sun), crop).settings["beam_photons"], 1 << 14);
  EXPECT_EQ(render(scene(0.3, 256, "4096", sun), crop).settings["beam_photons"], 1 << 16);
  EXPECT_EQ(render(scene(10.0, 256, "4096", sun), crop).settings["beam_photons"], 1 << 14);
  const std::string spot =
      R"({"type": "spot", "position": [0.5, 6, 0], "direction": [0, -1, 0], "intensity": 10.0, "cone_angle_deg": 60})";
  const RenderResult first = render(scene(0.3, 256, "\"auto\"", sun + ", " + spot), crop);
  EXPECT_EQ(first.settings["beam_photons"], 1 << 16);
  const Scene again = parse_scene(nlohmann::json::parse(meta(first, "nimbus/scene")), "header", ".");
  ASSERT_EQ(again.lights.size(), 2u);
  const RenderResult second = render(again, crop);
  ASSERT_EQ(second.image.rgb.size(), first.image.rgb.size());
  EXPECT_EQ(
      std::memcmp(second.image.rgb.data(), first.image.rgb.data(), first.image.rgb.size() * sizeof(float)),
      0);
}

// "auto" beam photons: 2^13 sqrt(pixels / 128^2) per light (at most 2^15), and 2^15 sqrt(pixels / 128^2) for a
// light whose forward peak the camera looks into (its light travels towards the camera within the peak's cut
// angle, about 37 degrees for HG 0.8, plus the media's size on the image): a crop of a 256 x 256 image of a
// backlit sphere traces 2^16 (2048 x 2048: 2^18, the most) and the 8 x 8 image 2^15; a side-lit sphere and a
// spot light (which the beam grid does not trace) 2^14 (8 x 8: 2^13, 2048 x 2048: 2^15, the most), a camera
// inside the media 2^16 for any light; with lights of both kinds the header says "auto" (and renders the same
// image again); a count given is kept. (The sphere, of optical radius 10, is not thin; thin media: the test
// above.)
TEST(RenderSettings, AutoBeamPhotonsFollowThePixelsWhereTheCameraLooksIntoTheForwardPeak) {
  const auto scene = [](const std::string& lights, int size) {
    return test::scene_from_json("{" + test::camera_json(size, size) + R"(,
      "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 10.0,
                 "phase": {"type": "hg", "g": 0.8}}],
      "lights": [)" + lights + R"(],
      "integrator": {"type": "mfs", "spp": 1, "photons": 4096, "scatter_grid_resolution": 8}})");
  };
  const std::string back = R"({"type": "directional", "direction": [0.3, -1, 0.2], "irradiance": 1.0})";
  const std::string side = R"({"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": 1.0})";
  const std::string behind = R"({"type": "point", "position": [0.5, 6, 0], "intensity": 10.0})";
  const std::string beside = R"({"type": "point", "position": [6, 0, 0.5], "intensity": 10.0})";
  RenderOptions crop;
  crop.region = Region{128, 128, 129, 129};
  EXPECT_EQ(render(scene(back, 256), crop).settings["beam_photons"], 1 << 16);
  EXPECT_EQ(render(scene(behind, 256), crop).settings["beam_photons"], 1 << 16);
  EXPECT_EQ(render(scene(back, 8)).settings["beam_photons"], 1 << 15);
  EXPECT_EQ(render(scene(side, 256), crop).settings["beam_photons"], 1 << 14);
  EXPECT_EQ(render(scene(side, 8)).settings["beam_photons"], 1 << 13);
  EXPECT_EQ(render(scene(beside, 256), crop).settings["beam_photons"], 1 << 14);
  const RenderResult both = render(scene(back + "," + side, 256), crop);
  EXPECT_EQ(both.settings["beam_photons"], "auto");
  const Scene again = parse_scene(nlohmann::json::parse(meta(both, "nimbus/scene")), "header", ".");
  const RenderResult both2 = render(again, crop);
  ASSERT_EQ(both2.image.rgb.size(), both.image.rgb.size());
  EXPECT_EQ(std::memcmp(both2.image.rgb.data(), both.image.rgb.data(), both.image.rgb.size() * sizeof(float)),
            0);
  crop.region = Region{1000, 1000, 1001, 1001};
  EXPECT_EQ(render(scene(back, 2048), crop).settings["beam_photons"], 1 << 18);  // at most 8 x 2^15
  EXPECT_EQ(render(scene(side, 2048), crop).settings["beam_photons"], 1 << 15);  // at most 2^15
  crop.region = Region{128, 128, 129, 129};
  const std::string spot =
      R"({"type": "spot", "position": [0.5, 6, 0], "direction": [0, -1, 0], "intensity": 10.0, "cone_angle_deg": 60})";
  EXPECT_EQ(render(scene(spot, 256), crop).settings["beam_photons"],
            1 << 14);  // the beam grid traces no spot
  // A camera inside the media's bounds may look anywhere: every light is counted as seen along its peak.
  Scene inside = scene(side, 256);
  inside.media[0].shape = SphereShape{Vec3(0.0), 8.0};
  EXPECT_EQ(render(inside, crop).settings["beam_photons"], 1 << 16);
  Scene given = scene(back, 256);
  given.integrator.options["beam_photons"] = 1000;
  EXPECT_EQ(render(given, crop).settings["beam_photons"], 1000);
}

// "auto" exact_light_transmittance: the closed-form chord for one constant-density sphere or box (the
// same image as asking for it), the shadow maps otherwise (here: two spheres).
TEST(RenderSettings, AutoExactLightTransmittanceIsTheChordForOneShape) {
  const std::string mfs = R"({"type": "mfs", "spp": 1, "photons": 4096, "beam_photons": 1024)";
  const RenderResult a = render(settings_sphere_scene(mfs + "}"));
  EXPECT_EQ(a.settings["exact_light_transmittance"], true);
  const RenderResult b = render(settings_sphere_scene(mfs + R"(, "exact_light_transmittance": true})"));
  ASSERT_EQ(a.image.rgb.size(), b.image.rgb.size());
  EXPECT_EQ(std::memcmp(a.image.rgb.data(), b.image.rgb.data(), a.image.rgb.size() * sizeof(float)), 0);
  const RenderResult c = render(settings_sphere_scene(mfs + R"(, "exact_light_transmittance": false})"));
  EXPECT_EQ(c.settings["exact_light_transmittance"], false);
  EXPECT_NE(std::memcmp(a.image.rgb.data(), c.image.rgb.data(), a.image.rgb.size() * sizeof(float)), 0);
  const Scene two = test::scene_from_json("{" + test::camera_json(8, 6) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [-0.5, 0, 0], "radius": 0.6}, "sigma_s": 3.0, "phase": {"type": "hg", "g": 0.8}},
              {"shape": {"type": "sphere", "center": [0.5, 0, 0], "radius": 0.6}, "sigma_s": 2.0, "phase": {"type": "hg", "g": 0.8}}],
    "lights": [{"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": 1.0}],
    "integrator": )" + mfs + "}}");
  EXPECT_EQ(render(two).settings["exact_light_transmittance"], false);
}

// Isotropic media (no peak: "auto" f = g^2 = 0): the scatter grid keeps one band, the fluence (the camera
// side reads it through the phase function's moments, 0 for l >= 1), and there is no beam grid (the
// peak-only beam is the unscattered light, which the straight beam has exactly). The image is the one with
// three bands asked for, bit for bit. HG 0.8, and a scene with an HG medium beside an isotropic one, keep
// three bands and the beam grid; a number given is kept.
TEST(RenderSettings, AutoBandsAndBeamPhotonsForIsotropicMedia) {
  const auto scene = [](const std::string& phase, const std::string& integrator, const std::string& second) {
    return test::scene_from_json("{" + test::camera_json(8, 6) + R"(,
      "media": [{"shape": {"type": "sphere", "center": [-0.3, 0, 0], "radius": 0.8}, "sigma_s": 2.0,
                 "sigma_a": 0.2, "phase": )" +
                                 phase + "}" + second + R"(],
      "lights": [{"type": "directional", "direction": [-1, 0.3, 0.2], "irradiance": 1.0}],
      "integrator": {"type": "mfs", "spp": 1, "photons": 4096)" +
                                 integrator + "}}");
  };
  const std::string iso = R"({"type": "isotropic"})", hg0 = R"({"type": "hg", "g": 0.0})";
  const std::string hg = R"({"type": "hg", "g": 0.8})";
  const RenderResult a = render(scene(iso, "", ""));
  EXPECT_EQ(a.settings["scatter_grid_bands"], 1);
  EXPECT_EQ(a.settings["beam_photons"], 0);
  const RenderResult b = render(scene(iso, R"(, "scatter_grid_bands": 3, "beam_photons": 0)", ""));
  EXPECT_EQ(b.settings["scatter_grid_bands"], 3);
  ASSERT_EQ(a.image.rgb.size(), b.image.rgb.size());
  EXPECT_EQ(std::memcmp(a.image.rgb.data(), b.image.rgb.data(), a.image.rgb.size() * sizeof(float)), 0);
  EXPECT_EQ(render(scene(hg0, "", "")).settings["scatter_grid_bands"], 1);
  const RenderResult h = render(scene(hg, "", ""));
  EXPECT_EQ(h.settings["scatter_grid_bands"], 3);
  EXPECT_GT(h.settings["beam_photons"].get<int>(), 0);
  const std::string beside = R"(, {"shape": {"type": "sphere", "center": [0.6, 0, 0], "radius": 0.3},
                                   "sigma_s": 2.0, "phase": {"type": "hg", "g": 0.8}})";
  const RenderResult mixed = render(scene(iso, "", beside));
  EXPECT_EQ(mixed.settings["scatter_grid_bands"], 3);
  EXPECT_GT(mixed.settings["beam_photons"].get<int>(), 0);
  EXPECT_EQ(render(scene(iso, R"(, "scatter_grid_bands": 2)", "")).settings["scatter_grid_bands"], 2);
}

TEST(RenderSettings, OverridesAreWhatTheHeaderSays) {
  const Scene scene =
      settings_sphere_scene(R"({"type": "pathtrace", "spp": 2, "seed": 5, "max_wide_scatters": 1})");
  RenderOptions o;
  o.integrator = "single";
  o.spp = 1;
  const RenderResult r = render(scene, o);
  // Another integrator starts from its own defaults; the scene's pathtrace fields do not follow it.
  EXPECT_EQ(r.settings["type"], "single");
  EXPECT_EQ(r.settings["spp"], 1);
  EXPECT_EQ(r.settings["seed"], 5);
  EXPECT_FALSE(r.settings.contains("max_wide_scatters"));
  EXPECT_EQ(r.settings["tau_step"], 0.1);
  EXPECT_EQ(nlohmann::json::parse(meta(r, "nimbus/scene"))["integrator"], r.settings);
  EXPECT_EQ(meta(r, "nimbus/integrator"), "single");

  // The same integrator keeps the scene's fields.
  o.integrator = "pathtrace";
  const RenderResult same = render(scene, o);
  EXPECT_EQ(same.settings["max_wide_scatters"], 1);
  EXPECT_EQ(same.settings["peak_fraction"], "auto");
}

// A scene without spp renders its integrator's default (include/nimbus/scene.h, default_spp: the best
// error per second), and an integrator switched on the command line takes its own, not the scene's.
TEST(RenderSettings, AnIntegratorWithoutSppTakesItsOwnDefault) {
  const Scene scene = settings_sphere_scene(R"({"type": "pathtrace"})", 4, 3);
  ASSERT_FALSE(scene.integrator.spp_given);
  RenderOptions o;
  o.integrator = "mfs";
  const RenderResult r = render(scene, o);
  EXPECT_EQ(r.settings["spp"], default_spp("mfs"));
  EXPECT_EQ(meta(r, "nimbus/spp"), std::to_string(default_spp("mfs")));
  EXPECT_NE(default_spp("mfs"), default_spp("pathtrace"));
}

}  // namespace
}  // namespace nimbus
