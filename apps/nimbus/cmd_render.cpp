// nimbus render: placeholder until the scene and integrators land.
#include "commands.h"

namespace nimbus::cli {

void add_render_command(CLI::App& app, Action& action) {
  auto* cmd = app.add_subcommand("render", "(not yet implemented)");
  cmd->callback([&action] { action = [] { return 1; }; });
}

}  // namespace nimbus::cli
