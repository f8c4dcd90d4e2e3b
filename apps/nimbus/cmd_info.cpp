// nimbus info: not yet implemented (stub registered so the CLI layout is fixed).
#include "commands.h"

namespace nimbus::cli {

void add_info_command(CLI::App& app, Action& action) {
  auto* cmd = app.add_subcommand("info", "(not yet implemented)");
  cmd->callback([&action] { action = [] { throw CLI::RuntimeError("not yet implemented", 1); return 1; }; });
}

}  // namespace nimbus::cli
