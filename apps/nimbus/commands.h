// The nimbus CLI: each subcommand lives in its own cmd_*.cpp and registers itself here.
// A subcommand's callback stores the action to run after parsing; main() runs it and turns
// nimbus::Error into a message on stderr and exit code 2.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace nimbus::cli {

using Action = std::function<int()>;

// Registers every subcommand (and --version) on `app`; parsing stores the chosen action in `action`.
void build_app(CLI::App& app, Action& action);

void add_render_command(CLI::App& app, Action& action);
void add_compare_command(CLI::App& app, Action& action);
void add_info_command(CLI::App& app, Action& action);
void add_convert_command(CLI::App& app, Action& action);
void add_beam_command(CLI::App& app, Action& action);
void add_slab_command(CLI::App& app, Action& action);
void add_merge_command(CLI::App& app, Action& action);
void add_lidar_command(CLI::App& app, Action& action);

// Throws nimbus::Error (naming `option`) unless `path` names a file in an existing folder: checked before
// the work, so that a long run never ends in a path it cannot write.
void check_output_path(const std::string& path, const std::string& option);

// Writes `text` to `path` (or stdout for "" and "-"), atomically; false, with an error on stderr, when the
// file cannot be written. The CSV output of beam, slab and lidar.
bool write_text(const std::string& path, const std::string& text);

// Exit codes.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;   // the run itself failed (I/O error writing, cancelled)
inline constexpr int kExitBadInput = 2;  // bad arguments, scene, volume or image

}  // namespace nimbus::cli
