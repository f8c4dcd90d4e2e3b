// nimbus merge A.exr B.exr ... -o OUT.exr: crops (render --region) assemble into the frame and renders
// of disjoint sample ranges (render --samples) into the render of all their samples (nimbus/merge.h).
// Incompatible inputs: `nimbus: error: FILE: FIELD differs ...`, exit 2, nothing written.
#include <fmt/format.h>

#include <string>
#include <vector>

#include "commands.h"
#include "nimbus/error.h"
#include "nimbus/image.h"
#include "nimbus/merge.h"

namespace nimbus::cli {

namespace {

struct MergeArgs {
  std::vector<std::string> inputs;
  std::string output;
  bool quiet = false;
};

int run_merge(const MergeArgs& args) {
  check_output_path(args.output, "--output");
  std::string ext = std::filesystem::path(args.output).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".exr")
    throw Error(fmt::format("--output: {}: the merged image must be an .exr file (it keeps the film state)",
                            args.output));
  std::vector<std::filesystem::path> files(args.inputs.begin(), args.inputs.end());
  const MergeResult r = merge_renders(files);
  write_exr(args.output, r.image, r.metadata, &r.state);
  if (!args.quiet)
    fmt::print(stderr, "nimbus: merged {} files: {}x{} at ({}, {}), samples {}..{} ({} spp) -> {}\n",
               files.size(), r.image.width, r.image.height, r.image.origin_x, r.image.origin_y,
               r.sample_start, r.sample_start + r.state.spp - 1, r.state.spp, args.output);
  return kExitOk;
}

}  // namespace

void add_merge_command(CLI::App& app, Action& action) {
  auto args = std::make_shared<MergeArgs>();
  auto* cmd = app.add_subcommand(
      "merge",
      "Merge nimbus EXRs of one frame: tiles (render --region) into the frame, disjoint sample ranges "
      "(render --samples START:COUNT) into the render of all their samples");
  cmd->add_option("inputs", args->inputs, "nimbus EXR renders (each carries its film state)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", args->output, "The merged EXR")->required();
  cmd->add_flag("-q,--quiet", args->quiet, "No summary");
  cmd->callback([args, &action] { action = [args] { return run_merge(*args); }; });
}

}  // namespace nimbus::cli
