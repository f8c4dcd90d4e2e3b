// nimbus convert IN.exr OUT.(png|exr): re-encode an image, e.g. an sRGB PNG of an EXR render at a chosen
// exposure. The output is written atomically; bad input: `nimbus: error: FILE: message`, exit 2.
#include <memory>
#include <string>

#include "commands.h"
#include "nimbus/image.h"

namespace nimbus::cli {

namespace {

struct ConvertArgs {
  std::string input, output;
  double exposure = 0.0;
  bool alpha = false;
};

int run_convert(const ConvertArgs& args) {
  ImageMetadata meta;
  const Image img = read_exr(args.input, &meta);
  write_image(args.output, img, meta, args.exposure, args.alpha);
  return kExitOk;
}

}  // namespace

void add_convert_command(CLI::App& app, Action& action) {
  auto args = std::make_shared<ConvertArgs>();
  auto* cmd = app.add_subcommand("convert", "Convert an EXR image to PNG (sRGB, with exposure) or EXR");
  cmd->add_option("input", args->input, "Input image (EXR)")->required();
  cmd->add_option("output", args->output, "Output image: .png (sRGB) or .exr")->required();
  cmd->add_option("--exposure", args->exposure, "Exposure in stops for PNG output")
      ->check(CLI::Range(-64.0, 64.0));
  cmd->add_flag(
      "--alpha", args->alpha,
      "PNG output: keep the EXR's alpha (an RGBA PNG with straight colour) instead of the image over black");
  cmd->callback([args, &action] { action = [args] { return run_convert(*args); }; });
}

}  // namespace nimbus::cli
