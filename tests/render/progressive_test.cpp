// Progressive and resumable renders: passes of 1, 2, 4, ... spp; a render stopped (cancel, time budget)
// is the whole image of its last pass; a film state resumed gives, bit for bit, the render made in one go,
// whatever the threads; the film state survives an EXR round trip.
#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <map>

#include "nimbus/error.h"
#include "nimbus/image.h"
#include "nimbus/render.h"
#include "scene/edges.h"
#include "support/bitwise.h"
#include "support/scenes.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

// `integrator`: the integrator block's type and its own fields, e.g. R"("pathtrace")".
Scene test_scene(const std::string& integrator) {
  return test::scene_from_json("{" + test::camera_json(20, 16) + R"(,
    "media": [{"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "sigma_s": 4.0,
               "sigma_a": 0.5, "phase": {"type": "hg", "g": 0.6}}],
    "lights": [{"type": "directional", "direction": [1, 1, -1], "irradiance": 2.0},
               {"type": "environment", "radiance": 0.2}],
    "film": {"layers": ["depth", "direct", "indirect", "samples"]},
    "integrator": {"type": )" + integrator +
                               R"(, "spp": 8, "seed": 5}})");
}

void expect_same_image(const RenderResult& a, const RenderResult& b) {
  EXPECT_TRUE(test::same_floats(a.image.rgb, b.image.rgb));
  EXPECT_TRUE(test::same_floats(a.image.alpha, b.image.alpha));
  ASSERT_EQ(a.image.channels.size(), b.image.channels.size());
  for (size_t c = 0; c < a.image.channels.size(); ++c)
    EXPECT_TRUE(test::same_floats(a.image.channels[c].data, b.image.channels[c].data))
        << a.image.channels[c].name;
}

TEST(Progressive, PassesDoubleTheSamples) {
  EXPECT_EQ(next_pass_spp(0, 64), 1);
  EXPECT_EQ(next_pass_spp(1, 64), 2);
  EXPECT_EQ(next_pass_spp(2, 64), 4);
  EXPECT_EQ(next_pass_spp(32, 64), 64);
  EXPECT_EQ(next_pass_spp(3, 8), 6);  // a resumed render doubles from where it is
  EXPECT_EQ(next_pass_spp(5, 8), 8);
  EXPECT_EQ(next_pass_spp(0, 1), 1);
}

TEST(Progressive, ResumedRenderEqualsOneRenderBitForBit) {
  // mfs: its photon grids are made again from the seed, the same on any thread count.
  for (const std::string integrator : {R"("pathtrace")", R"("mfs", "photons": 4096, "beam_photons": 1024)"}) {
    SCOPED_TRACE(integrator);
    const Scene scene = test_scene(integrator);
    RenderOptions one;
    one.threads = 1;
    const RenderResult whole = render(scene, one);
    ASSERT_EQ(whole.spp, 8);
    RenderOptions first;
    first.threads = 2;
    first.tile_size = 7;
    first.spp = 3;
    const RenderResult part = render(scene, first);
    ASSERT_EQ(part.spp, 3);
    EXPECT_FALSE(part.partial);
    RenderOptions rest;
    rest.threads = 2;
    rest.resume = &part.state;
    const RenderResult resumed = render(scene, rest);
    EXPECT_EQ(resumed.spp, 8);
    expect_same_image(whole, resumed);
    // And the resumed image differs from a render of fewer samples (the test can fail).
    EXPECT_FALSE(test::same_floats(part.image.rgb, resumed.image.rgb));
  }
}

// mfs's edge_samples n: an outline pixel's samples at s spp are the pixel's samples at n s spp without it
// (the same sample indices, so the same positions and random streams), bit for bit; beside it n / 4 s;
// elsewhere s. So nothing is biased, and resumed or windowed renders stay exact.
TEST(Progressive, OutlinePixelsTakeTheSamplesOfAHigherSpp) {
  const std::string mfs = R"("mfs", "photons": 4096, "beam_photons": 1024, "edge_samples": )";
  const Scene edges = test_scene(mfs + "8"), plain = test_scene(mfs + "1");
  const int W = 20, H = 16;
  const SceneContext ctx(edges);
  const std::vector<PixelEdge> classes = edge_pixels(ctx, Region{0, 0, W, H});
  RenderOptions o;
  o.threads = 2;
  o.spp = 1;
  const RenderResult r = render(edges, o);
  std::map<int, RenderResult> without;
  for (int spp : {1, 2, 8}) {
    o.spp = spp;
    without[spp] = render(plain, o);
  }
  std::map<PixelEdge, int> seen;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const size_t i = size_t(y) * W + x;
      const int k = classes[i] == PixelEdge::outline ? 8 : classes[i] == PixelEdge::beside ? 2 : 1;
      EXPECT_EQ(r.state.counts[i], uint32_t(k)) << x << " " << y;
      EXPECT_EQ(std::memcmp(r.image.pixel(x, y), without[k].image.pixel(x, y), 3 * sizeof(float)), 0)
          << x << " " << y;
      ++seen[classes[i]];
    }
  EXPECT_GT(seen[PixelEdge::outline], 10);
  EXPECT_GT(seen[PixelEdge::beside], 10);
  // A film whose outline pixels took other counts (an earlier nimbus, other edge_samples) is not continued.
  RenderOptions more;
  more.threads = 2;
  more.spp = 2;
  more.resume = &r.state;
  try {
    render(test_scene(mfs + "4"), more);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("resume: pixel"), std::string::npos) << e.what();
  }
  EXPECT_EQ(render(edges, more).spp, 2);  // the same edge_samples continues it
  // A window through the outline is the whole image's crop (its pixels beside an outline pixel outside it
  // take their samples too).
  o.spp = 1;
  o.region = Region{3, 2, 15, 11};
  const RenderResult w = render(edges, o);
  for (int y = 2; y < 11; ++y)
    for (int x = 3; x < 15; ++x)
      EXPECT_EQ(std::memcmp(w.image.pixel(x - 3, y - 2), r.image.pixel(x, y), 3 * sizeof(float)), 0)
          << x << " " << y;
}

TEST(Progressive, CancelledRenderIsTheWholeImageOfItsLastPass) {
  const Scene scene = test_scene(R"("pathtrace")");
  const int64_t pixels = 20 * 16;
  std::atomic<bool> cancel{false};
  RenderOptions opt;
  opt.threads = 1;
  opt.tile_size = 4;
  opt.cancel = &cancel;
  // Cancel inside the third pass (samples 2 and 3): the image is the one of 2 spp.
  opt.progress = [&](int64_t done, int64_t, int64_t) {
    if (done > 2 * pixels) cancel = true;
  };
  const RenderResult r = render(scene, opt);
  EXPECT_TRUE(r.partial);
  EXPECT_EQ(r.spp, 2);
  RenderOptions two;
  two.threads = 2;
  two.spp = 2;
  expect_same_image(render(scene, two), r);
  // The samples layer says so in every pixel.
  for (const ImageChannel& c : r.image.channels) {
    if (c.name != "samples.X") continue;
    for (float v : c.data) ASSERT_EQ(v, 2.0f);
  }
}

TEST(Progressive, TimeBudgetKeepsTheFirstPassAndStopsCleanly) {
  const Scene scene = test_scene(R"("pathtrace")");
  RenderOptions opt;
  opt.threads = 1;
  opt.spp = 1 << 20;
  opt.time_limit = 1e-6;  // past before the first pass ends: that pass is kept, no other is started
  const RenderResult r = render(scene, opt);
  EXPECT_TRUE(r.time_limited);
  EXPECT_FALSE(r.partial);
  EXPECT_EQ(r.spp, 1);
  RenderOptions one;
  one.spp = 1;
  expect_same_image(render(scene, one), r);
  opt.time_limit = -1.0;
  EXPECT_THROW(render(scene, opt), Error);
}

TEST(Progressive, ResumeRejectsAMismatchedState) {
  const Scene scene = test_scene(R"("pathtrace")");
  RenderOptions first;
  first.spp = 2;
  const RenderResult part = render(scene, first);
  FilmState wrong = part.state;
  wrong.layers.pop_back();
  RenderOptions rest;
  rest.resume = &wrong;
  EXPECT_THROW(render(scene, rest), Error);
  rest.resume = &part.state;
  rest.spp = 1;  // fewer samples than the state holds
  EXPECT_THROW(render(scene, rest), Error);
  rest.spp = 4;
  rest.deep_samples = 4;
  EXPECT_THROW(render(scene, rest), Error);
}

TEST(Progressive, FilmStateSurvivesTheExr) {
  const test::ScratchDir scratch("progressive_exr");
  const Scene scene = test_scene(R"("pathtrace")");
  RenderOptions opt;
  opt.spp = 3;
  const RenderResult r = render(scene, opt);
  const auto file = scratch.path / "a.exr";
  write_exr(file, r.image, r.metadata, &r.state);
  const FilmState st = read_exr_state(file);
  EXPECT_EQ(st.spp, 3);
  EXPECT_EQ(st.counts, r.state.counts);
  ASSERT_EQ(st.layers.size(), r.state.layers.size());
  for (const FilmState::Layer& l : r.state.layers) {
    bool found = false;
    for (const FilmState::Layer& m : st.layers)
      if (m.name == l.name) {
        found = true;
        EXPECT_EQ(m.channels, l.channels);
        EXPECT_EQ(m.fraction_bits, l.fraction_bits);
        EXPECT_TRUE(m.sums == l.sums) << l.name;
      }
    EXPECT_TRUE(found) << l.name;
  }
  // The image part reads as a one-part file does.
  const Image back = read_exr(file);
  EXPECT_TRUE(test::same_floats(back.rgb, r.image.rgb));
  // A file without a state names itself.
  write_exr(scratch.path / "b.exr", r.image);
  try {
    read_exr_state(scratch.path / "b.exr");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("b.exr"), std::string::npos);
  }
  // A state whose counts disagree with its spp (more samples than even an outline pixel takes) is refused
  // at writing.
  FilmState bad = r.state;
  bad.counts[0] = uint32_t(bad.spp) * kMaxEdgeSamples + 1;
  EXPECT_THROW(write_exr(scratch.path / "c.exr", r.image, {}, &bad), Error);
  EXPECT_FALSE(std::filesystem::exists(scratch.path / "c.exr"));
}

}  // namespace
}  // namespace nimbus
