// `nimbus info` run as a user would: the grids of the shared test volumes, a missing file, --help.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <string>

#include "io/vdb_test_util.h"
#include "support/cli.h"

namespace nimbus {
namespace {

using test::kCloud;
using test::kSmoke;
using test::shared_volume;

using test::run_cli;

TEST(VdbCli, InfoListsTheGrids) {
  NIMBUS_REQUIRE_FILE(shared_volume(kCloud));
  NIMBUS_REQUIRE_FILE(shared_volume(kSmoke));
  test::CliRun r = run_cli("info " + shared_volume(kCloud).string());
  EXPECT_EQ(r.rc, 0) << r.out;
  EXPECT_NE(r.out.find("grid 0: density"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("415642"), std::string::npos);
  EXPECT_NE(r.out.find("[-66, -21, -90] .. [59, 64, 63]"), std::string::npos);
  EXPECT_NE(r.out.find("fog volume"), std::string::npos);
  r = run_cli("info " + shared_volume(kSmoke).string());
  EXPECT_EQ(r.rc, 0) << r.out;
  EXPECT_NE(r.out.find("(unnamed)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1049275"), std::string::npos);
  EXPECT_NE(r.out.find("[1, 2, 1] .. [111, 223, 112]"), std::string::npos);
  r = run_cli("info /nonexistent/cloud.vdb");
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.out.find("nimbus: error: /nonexistent/cloud.vdb: no such file"), std::string::npos) << r.out;
  r = run_cli("info --help");
  EXPECT_EQ(r.rc, 0);
  EXPECT_NE(r.out.find(".nvdb"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace nimbus
