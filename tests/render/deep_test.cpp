// Deep pixels: segments merged into at most N deep samples keep the pixel's colour and alpha, and a
// rendered deep image, flattened front to back, is the flat RGBA of a transparent film.
#include "render/deep.h"

#include <gtest/gtest.h>

#include "nimbus/render.h"
#include "support/scenes.h"

namespace nimbus {
namespace {

TEST(Deep, MergedSamplesKeepThePixelsColourAndAlpha) {
  // A medium of 200 steps, each removing 1 % of what is left and adding colour.
  std::vector<DeepSegment> segments;
  double T = 1.0;
  Rgb C(0.0);
  for (int k = 0; k < 200; ++k) {
    const double T1 = T * 0.99;
    const Rgb L = Rgb(0.3, 0.2, 0.1) * (T - T1);
    segments.push_back({1.0 + 0.01 * k, 1.01 + 0.01 * k, L, T - T1});
    C += L;
    T = T1;
  }
  segments.push_back({5.0, 5.0, Rgb(0.05), 0.0});  // a point with colour and no alpha
  C += Rgb(0.05);
  for (const int n : {1, 3, 32}) {
    std::vector<DeepSample> out;
    merge_deep_segments(segments, 0.5, n, &out);  // weight 1/2: one of two samples
    ASSERT_LE(int(out.size()), n);
    ASSERT_FALSE(out.empty());
    double r = 0.0, a = 0.0;
    float last = 0.0f;
    for (const DeepSample& s : out) {
      EXPECT_LE(s.z, s.z_back);
      EXPECT_GE(s.z, last);  // sorted and not overlapping
      last = s.z_back;
      EXPECT_GE(s.a, 0.0f);
      EXPECT_LE(s.a, 1.0f);
      r += (1.0 - a) * s.r;
      a += (1.0 - a) * s.a;
    }
    EXPECT_NEAR(r, 0.5 * C[0], 1e-6) << n;
    EXPECT_NEAR(a, 0.5 * (1.0 - T), 1e-6) << n;
    EXPECT_FLOAT_EQ(out.front().z, 1.0f);
    EXPECT_FLOAT_EQ(out.back().z_back, 5.0f);
  }
}

TEST(Deep, FlattenedDeepImageIsTheFlatRgba) {
  const std::string lights = R"([{"type": "directional", "direction": [1, 1, -1], "irradiance": 2.0},
                                 {"type": "point", "position": [0, -2, 1], "intensity": 1.0},
                                 {"type": "environment", "radiance": [0.1, 0.2, 0.4]}])";
  nlohmann::json doc = nlohmann::json::parse("{" + test::camera_json(12, 10) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": [2.0, 3.0, 4.0],
               "sigma_a": 0.3, "phase": {"type": "hg", "g": 0.6}},
              {"shape": {"type": "cloud", "center": [0.3, 0.5, 0.2], "radius": 0.7, "resolution": 16},
               "sigma_s": 8.0, "phase": {"type": "isotropic"}}],
    "lights": )" + lights + ", \"film\": {\"transparent\": true}}");
  for (const char* type : {"pathtrace", "single", "octave", "mfs"}) {
    doc["integrator"] = {{"type", type}, {"spp", 3}, {"seed", 2}};
    if (std::string(type) == "mfs" || std::string(type) == "octave")
      doc["integrator"]["shadow_map_resolution"] = 16;
    if (std::string(type) == "mfs") {
      doc["integrator"]["photons"] = 4000;
      doc["integrator"]["scatter_grid_resolution"] = 8;
      doc["integrator"]["beam_photons"] = 0;
    }
    RenderOptions options;
    options.threads = 2;
    options.deep_samples = 8;
    const RenderResult r = render(parse_scene(doc, "test.json", "."), options);
    ASSERT_EQ(r.deep.offsets.size(), size_t(12 * 10 + 1));
    const Image flat = flatten(r.deep);
    size_t most = 0;
    for (size_t i = 0; i + 1 < r.deep.offsets.size(); ++i) {
      most = std::max<size_t>(most, r.deep.offsets[i + 1] - r.deep.offsets[i]);
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(flat.rgb[3 * i + c], r.image.rgb[3 * i + c], 1e-3) << type << " pixel " << i;
      EXPECT_NEAR(flat.alpha[i], r.image.alpha[i], 1e-3) << type << " pixel " << i;
    }
    EXPECT_LE(most, 8u);
    EXPECT_GT(most, 1u) << type;
  }
}

}  // namespace
}  // namespace nimbus
