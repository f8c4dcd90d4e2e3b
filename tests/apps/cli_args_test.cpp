// Command-line arguments found wanting by hand next to the CLI fuzz target, which only parses
// (docs/reliability.md): each must exit with code 2 and a message naming the option.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "support/scratch_dir.h"

namespace nimbus {
namespace {

// Runs the CLI with `args`; returns (exit code, stderr).
std::pair<int, std::string> run(const std::string& args) {
  test::ScratchDir dir("cli_args");
  const std::string cmd =
      std::string(NIMBUS_CLI) + " " + args + " > /dev/null 2> " + (dir / "err.txt").string();
  const int status = std::system(cmd.c_str());
  std::ifstream err(dir / "err.txt");
  std::string text{std::istreambuf_iterator<char>(err), std::istreambuf_iterator<char>()};
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text};
}

TEST(CliArgs, SlabExtinctionThatOverflowsIsRefused) {
  const auto [code, err] = run("slab --mu-s 1e308 --mu-a 1e308 --g 0.5 --thickness 1 --photons 20");
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("--mu-s + --mu-a must be finite"), std::string::npos) << err;
}

}  // namespace
}  // namespace nimbus
