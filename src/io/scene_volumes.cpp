#include "io/scene_volumes.h"

#include <fmt/format.h>

#include "nimbus/error.h"
#include "nimbus/image.h"

namespace nimbus {

void load_vdb_shape(VdbShape& v, const std::filesystem::path& base_dir, const std::string& where,
                    const std::string& json_path) {
  throw Error(fmt::format("{}: {}: vdb media are not supported yet", where, json_path));
}

void build_cloud_shape(CloudShape& c) { throw Error("cloud shapes are not supported yet"); }

}  // namespace nimbus
// TEMPORARY until the vdb/img branches land.
namespace nimbus {
Scene builtin_demo_scene() { throw Error("demo not available yet"); }
void write_image(const std::filesystem::path&, const Image&, const ImageMetadata&, double) { throw Error("no image output yet"); }
}
