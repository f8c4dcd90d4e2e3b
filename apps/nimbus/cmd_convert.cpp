// nimbus convert IN.exr OUT.(png|exr): re-encode an image, e.g. an sRGB PNG of an EXR render at a chosen
// exposure; nimbus convert IN.vdb OUT.nvdb [--upsample N]: an OpenVDB volume's float grids as a NanoVDB
// file, optionally refined N times per axis (the same density field, N^3 times the voxels). The
// output is written atomically; bad input: `nimbus: error: FILE: message`, exit 2.
#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "io/vdb_convert.h"
#include "nimbus/error.h"
#include "nimbus/image.h"

namespace nimbus::cli {

namespace {

struct ConvertArgs {
  std::string input, output;
  double exposure = 0.0;
  bool alpha = false;
  std::vector<std::string> grids;  // .vdb -> .nvdb: these grids (default every float grid)
  int upsample = 1;                // .vdb -> .nvdb: refine each grid by this factor per axis
};

std::string lower_ext(const std::string& p) {
  std::string e = std::filesystem::path(p).extension().string();
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

int run_convert(const ConvertArgs& args) {
  check_output_path(args.output, "output");
  const std::string in = lower_ext(args.input), out = lower_ext(args.output);
  if (in == ".vdb" || in == ".nvdb" || out == ".nvdb" || out == ".vdb") {
    if (in != ".vdb" || out != ".nvdb")
      throw Error(fmt::format("{} -> {}: volumes convert from .vdb (OpenVDB) to .nvdb (NanoVDB) only",
                              args.input, args.output));
    const std::vector<std::string> names =
        convert_vdb_to_nvdb(args.input, args.output, args.grids, args.upsample);
    fmt::print(stderr, "nimbus: {} grid{} ({}) -> {}\n", names.size(), names.size() == 1 ? "" : "s",
               fmt::join(names, ", "), args.output);
    return kExitOk;
  }
  if (!args.grids.empty()) throw Error("--grid: only for a .vdb -> .nvdb conversion");
  if (args.upsample != 1) throw Error("--upsample: only for a .vdb -> .nvdb conversion");
  ImageMetadata meta;
  const Image img = read_exr(args.input, &meta);
  write_image(args.output, img, meta, args.exposure, args.alpha);
  return kExitOk;
}

}  // namespace

void add_convert_command(CLI::App& app, Action& action) {
  auto args = std::make_shared<ConvertArgs>();
  auto* cmd = app.add_subcommand(
      "convert", "Convert an EXR image to PNG (sRGB, with exposure) or EXR, or an OpenVDB volume to NanoVDB");
  cmd->add_option("input", args->input, "Input image (EXR) or volume (.vdb)")->required();
  cmd->add_option("output", args->output, "Output image: .png (sRGB) or .exr; or volume: .nvdb")->required();
  cmd->add_option("--grid", args->grids,
                  "A .vdb's float grid to convert (repeatable; default: every float grid)");
  cmd->add_option("--upsample", args->upsample,
                  "A .vdb -> .nvdb conversion: refine each grid by this integer factor per axis (the same "
                  "trilinear density field on a finer lattice; 4 gives 64x the voxels)")
      ->check(CLI::Range(1, 16));
  cmd->add_option("--exposure", args->exposure, "Exposure in stops for PNG output")
      ->check(CLI::Range(-64.0, 64.0));
  cmd->add_flag(
      "--alpha", args->alpha,
      "PNG output: keep the EXR's alpha (an RGBA PNG with straight colour) instead of the image over black");
  cmd->callback([args, &action] { action = [args] { return run_convert(*args); }; });
}

}  // namespace nimbus::cli
