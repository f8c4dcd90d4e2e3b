// libFuzzer target: the CLI's argument parsing. The input is split into argv at NUL bytes (and
// newlines), prefixed with "nimbus", and parsed by the same CLI11 command tree main() builds
// (build_app in apps/nimbus/app.cpp). Only parsing runs: the action a subcommand stores is never
// called, so nothing renders, reads or writes files. CLI::ParseError (bad arguments, --help,
// --version) is a clean rejection; anything else escaping, or a sanitizer report, is a bug.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "commands.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > 4096) return 0;
  std::vector<std::string> args{"nimbus"};
  std::string cur;
  for (size_t i = 0; i < size; ++i) {
    const char c = static_cast<char>(data[i]);
    if (c == '\0' || c == '\n') {
      args.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) args.push_back(cur);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  CLI::App app;
  nimbus::cli::Action action;
  nimbus::cli::build_app(app, action);
  try {
    app.parse(static_cast<int>(args.size()), argv.data());
  } catch (const CLI::ParseError&) {
  }
  return 0;
}
