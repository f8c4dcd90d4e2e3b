// The CLI loads its OpenVDB module (lib/nimbus/libnimbus_openvdb.so; src/io/vdb_internal.h) only to read
// a .vdb file: a scene of .nvdb files renders without it, and a missing or broken module is a clear
// error naming the volume file and the module, exit 2. $NIMBUS_OPENVDB_MODULE, where set, is the only
// place looked at. The installed layout is tested by tests/apps/install_test.sh.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "support/cli.h"
#include "support/scratch_dir.h"

namespace nimbus {
namespace {

namespace fs = std::filesystem;

#if NIMBUS_LAZY_OPENVDB_CLI
TEST(OpenVdbModule, LoadedOnlyForVdbFilesAndMissingItIsAClearError) {
  const test::ScratchDir dir("openvdb_module");
  const fs::path vdb = fs::path(NIMBUS_SOURCE_DIR) / "fuzz" / "data" / "tiny.vdb";
  const fs::path nvdb = dir / "t.nvdb";
  ASSERT_EQ(test::run_cli("convert " + vdb.string() + " " + nvdb.string()).rc, 0);
  test::write_vdb_scene(dir / "s.json", nvdb.string(), 8, 6, R"({"type": "mfs", "spp": 1})");
  const std::string missing = (dir / "no_such_module.so").string();
  const std::string env = "NIMBUS_OPENVDB_MODULE=" + missing + " ";
  // A NanoVDB scene and file never need OpenVDB.
  const test::CliRun render = test::run_cli_env(
      env, "render --quiet " + (dir / "s.json").string() + " -o " + (dir / "s.exr").string());
  EXPECT_EQ(render.rc, 0) << render.out;
  EXPECT_TRUE(fs::exists(dir / "s.exr"));
  EXPECT_EQ(test::run_cli_env(env, "info " + nvdb.string()).rc, 0);
  // A .vdb file does: the error names the file and where the module was looked for.
  const test::CliRun info = test::run_cli_env(env, "info " + vdb.string());
  EXPECT_EQ(info.rc, 2) << info.out;
  EXPECT_NE(info.out.find("nimbus: error: " + vdb.string() + ": "), std::string::npos) << info.out;
  EXPECT_NE(info.out.find(missing), std::string::npos) << info.out;
  // A file that is not a shared object: dlopen's reason, and nothing half-written.
  std::ofstream(dir / "broken.so") << "not a shared object\n";
  const test::CliRun broken = test::run_cli_env("NIMBUS_OPENVDB_MODULE=" + (dir / "broken.so").string() + " ",
                                                "convert " + vdb.string() + " " + (dir / "x.nvdb").string());
  EXPECT_EQ(broken.rc, 2) << broken.out;
  EXPECT_NE(broken.out.find("cannot load " + (dir / "broken.so").string()), std::string::npos) << broken.out;
  EXPECT_FALSE(fs::exists(dir / "x.nvdb"));
  // And the build's own module reads it.
  const test::CliRun found = test::run_cli("info " + vdb.string());
  EXPECT_EQ(found.rc, 0) << found.out;
  EXPECT_NE(found.out.find("active voxels 25"), std::string::npos) << found.out;
}
#endif

}  // namespace
}  // namespace nimbus
