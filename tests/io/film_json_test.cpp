// The scene's film block: parsed strictly, every error naming the JSON path.
#include <gtest/gtest.h>

#include "nimbus/error.h"
#include "support/scenes.h"

namespace nimbus {
namespace {

std::string with_film(const std::string& film) {
  return "{" + test::camera_json() + R"(, "media": [], "lights": [], "film": )" + film + "}";
}

std::string film_error(const std::string& film) {
  try {
    test::scene_from_json(with_film(film));
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(FilmJson, ParsesTransparencyAndLayers) {
  const Scene plain = test::scene_from_json("{" + test::camera_json() + R"(, "media": [], "lights": []})");
  EXPECT_FALSE(plain.film.transparent);
  EXPECT_TRUE(plain.film.layers.empty());
  const Scene s = test::scene_from_json(with_film(R"({"transparent": true, "layers": ["depth", "normal"]})"));
  EXPECT_TRUE(s.film.transparent);
  EXPECT_EQ(s.film.layers, (std::vector<std::string>{"depth", "normal"}));
  EXPECT_TRUE(test::scene_from_json(with_film("{}")).film.layers.empty());
}

TEST(FilmJson, BadFieldsAreErrorsNamingThePath) {
  EXPECT_EQ(film_error(R"({"transparent": 1})"),
            "test.json: /film/transparent: must be true or false, not a number");
  EXPECT_EQ(film_error(R"({"layers": "depth"})"), "test.json: /film/layers: must be an array of layer names");
  EXPECT_EQ(film_error(R"({"layers": ["depth", 3]})"),
            "test.json: /film/layers/1: must be a layer name (a string)");
  EXPECT_EQ(
      film_error(R"({"layers": ["depth", "zdepth"]})"),
      "test.json: /film/layers/1: unknown layer 'zdepth' (known: depth, transmittance, direct, indirect, "
      "albedo, normal, samples)");
  EXPECT_EQ(film_error(R"({"layers": ["depth", "depth"]})"),
            "test.json: /film/layers/1: layer 'depth' named twice");
  EXPECT_EQ(film_error(R"({"transparant": true})"),
            "test.json: /film/transparant: unknown field (known here: transparent)");
  EXPECT_EQ(film_error("[]"), "test.json: /film: must be an object, not an array");
}

}  // namespace
}  // namespace nimbus
