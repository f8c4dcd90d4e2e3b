// nimbus: the command-line front end. The only code that prints or exits.
#include <fmt/format.h>

#include <cstdio>
#include <exception>

#include "commands.h"
#include "nimbus/error.h"

int main(int argc, char** argv) {
  using namespace nimbus::cli;
  CLI::App app;
  Action action;
  build_app(app, action);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    fmt::print(stderr, "nimbus: error: {}\nRun with --help for more information.\n", e.what());
    return kExitBadInput;
  }
  try {
    return action ? action() : kExitOk;
  } catch (const nimbus::Cancelled& e) {
    fmt::print(stderr, "nimbus: cancelled\n");
    return kExitFailure;
  } catch (const nimbus::Error& e) {
    fmt::print(stderr, "nimbus: error: {}\n", e.what());
    return kExitBadInput;
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "nimbus: error: out of memory\n");
    return kExitFailure;
  } catch (const std::exception& e) {
    fmt::print(stderr, "nimbus: internal error: {}\n", e.what());
    return kExitFailure;
  }
}
