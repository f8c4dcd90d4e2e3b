// The scene's environment light (io/scene_environment.h).
#include "io/scene_environment.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfTestFile.h>
#include <fmt/format.h>

#include <cmath>

#include "io/scene_fields.h"
#include "io/transform_json.h"
#include "nimbus/error.h"
#include "scene/env_map.h"

namespace nimbus {

Image read_environment_image(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw Error(fmt::format("{}: no such file", path.string()));
  if (!Imf::isOpenExrFile(path.c_str()))
    throw Error(
        fmt::format("{}: not an OpenEXR file (an environment image must be an HDR .exr)", path.string()));
  try {
    const Imf::InputFile file(path.c_str());
    const Imf::ChannelList& channels = file.header().channels();
    for (const char* name : {"R", "G", "B"}) {
      const Imf::Channel* c = channels.findChannel(name);
      if (!c) throw Error(fmt::format("no {} channel (an environment image needs R, G and B)", name));
      if (c->type == Imf::UINT)
        throw Error(fmt::format("channel {} holds integers, not HDR half or float", name));
    }
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", path.string(), e.what()));
  } catch (const std::exception& e) {
    throw Error(fmt::format("{}: cannot read EXR: {}", path.string(), e.what()));
  }
  Image img = read_exr(path);
  for (float& v : img.rgb) {
    if (!std::isfinite(v)) throw Error(fmt::format("{}: a pixel is not finite", path.string()));
    v = std::max(v, 0.0f);
  }
  return img;
}

EnvironmentLight parse_environment_light(JsonObject& o, const std::filesystem::path& base_dir) {
  EnvironmentLight e;
  if (!o.has("file")) {
    for (const char* key : {"intensity", "transform"})
      if (o.has(key)) o.fail(key, "needs an environment image (\"file\")");
    e.radiance = o.rgb("radiance", 0.0);
    return e;
  }
  if (o.has("radiance")) o.fail("radiance", "conflicts with " + o.path_of("file") + " (one or the other)");
  e.radiance = Rgb(0.0);
  e.file = o.string("file");
  e.intensity = o.number("intensity", 0.0, 1e12, 1.0);
  if (o.present("transform")) {
    JsonObject t = o.object("transform");
    for (const char* key : {"scale", "translate", "matrix"})
      if (t.has(key)) t.fail(key, "an environment image takes rotations only (\"rotate\")");
    e.transform = parse_transform(t);
  }
  try {
    Image img = read_environment_image(resolve_scene_path(base_dir, e.file));
    e.map =
        std::make_shared<const EnvMap>(img.width, img.height, std::move(img.rgb), e.transform, e.intensity);
  } catch (const Error& err) {
    o.fail("file", err.what());
  }
  return e;
}

}  // namespace nimbus
