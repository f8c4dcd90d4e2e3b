// The whole command tree of the CLI, without running anything: main() and the CLI fuzz target
// (fuzz/cli_fuzz.cpp) build it the same way.
#include "commands.h"

namespace nimbus::cli {

void build_app(CLI::App& app, Action& action) {
  app.description(
      "nimbus: a renderer for forward-scattering participating media (clouds, smoke, fog, skin, "
      "water), with the multiple-forward-scattering model judged against an unbiased path tracer.");
  app.require_subcommand(1);
  app.set_version_flag("--version", "nimbus 0.1.0");
  add_render_command(app, action);
  add_compare_command(app, action);
  add_info_command(app, action);
  add_convert_command(app, action);
  add_beam_command(app, action);
  add_slab_command(app, action);
  add_merge_command(app, action);
  add_lidar_command(app, action);
}

}  // namespace nimbus::cli
