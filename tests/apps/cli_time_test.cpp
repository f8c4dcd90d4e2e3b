// `nimbus slab --time-edges` and `nimbus beam --time-edges` run as a user would: the CSV they promise,
// rows that sum to the steady values, and exit code 2 naming the argument on bad time edges.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "support/cli.h"

namespace {

using nimbus::test::CliRun;
using nimbus::test::run_cli;

TEST(CliTime, SlabWritesTimeRowsThatSumToTheSteadyValues) {
  const auto dir = nimbus::test::cli_temp_dir("cli_time_test");
  const auto out = dir / "time.csv";
  const CliRun r = run_cli(
      "slab --mu-s 1 --mu-a 0.1 --g 0.5 --thickness 1 --n 1.4 --photons 4000 --time-edges 1:3:4 "
      "--time-csv " +
      out.string());
  ASSERT_EQ(r.rc, 0) << r.out;
  std::map<std::string, double> steady;
  {
    std::stringstream ss(r.out);
    std::string name;
    double value, err;
    while (ss >> name >> value >> err) steady[name] = value;
  }
  std::ifstream in(out);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "tlo,thi,reflectance,reflectance_stderr,transmittance,transmittance_stderr");
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line)) rows.push_back(nimbus::test::split_csv(line));
  ASSERT_EQ(rows.size(), 6u);  // 0..1, four bins, 3..inf
  EXPECT_EQ(std::stod(rows.front()[0]), 0.0);
  EXPECT_EQ(std::stod(rows.front()[1]), 1.0);
  EXPECT_TRUE(std::isinf(std::stod(rows.back()[1])));
  double R = 0.0, T = 0.0;
  for (const auto& row : rows) {
    ASSERT_EQ(row.size(), 6u);
    R += std::stod(row[2]);
    T += std::stod(row[4]);
  }
  EXPECT_NEAR(R, steady["diffuse_reflectance"], 1e-6);
  EXPECT_NEAR(T, steady["transmittance"], 1e-6);
  // Causality: no transmission before n D = 1.4 (the row 0..1 and the bin 1..1.5 hold the unscattered
  // light at 1.4 and nothing earlier than 1).
  EXPECT_EQ(std::stod(rows[0][4]), 0.0);
  EXPECT_GE(std::stod(rows[1][4]), steady["unscattered_transmittance"] - 1e-7);
}

TEST(CliTime, BeamAddsDelayRowsForMcAndMfs) {
  const CliRun r = run_cli(
      "beam --phase gauss:0.01 --albedo 0.99 --depths 0.5,1 --photons 2000 --models mc,mfs "
      "--theta-edges 0,0.1,3.14159 --r-edges 0,1 --time-edges 0,0.001,0.01");
  ASSERT_EQ(r.rc, 0) << r.out;
  std::map<std::string, int> count;
  std::stringstream ss(r.out);
  std::string line;
  while (std::getline(ss, line)) {
    const auto v = nimbus::test::split_csv(line);
    if (v.size() == 9 && v[2].rfind("delay", 0) == 0) ++count[v[0] + ":" + v[2]];
  }
  for (const char* m : {"mc", "mfs"}) {
    EXPECT_EQ(count[std::string(m) + ":delay"], 2 * 3) << m;  // two bins and the tail, per depth
    EXPECT_EQ(count[std::string(m) + ":delay_mean"], 2) << m;
    EXPECT_EQ(count[std::string(m) + ":delay_variance"], 2) << m;
  }
}

std::vector<std::vector<std::string>> read_rows(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) rows.push_back(nimbus::test::split_csv(line));
  return rows;
}

TEST(CliTime, BeamJointTablesSumToTheDelayRows) {
  const auto dir = nimbus::test::cli_temp_dir("cli_time_test");
  const auto angle = dir / "angle.csv", radius = dir / "radius.csv";
  const CliRun r = run_cli(
      "beam --phase hg:0.9 --albedo 0.99 --depths 0.5,1 --photons 4000 --models mc,mfs,gsa "
      "--theta-edges 0,0.1,0.5 --r-edges 0,0.3,1 --time-edges 0.01,0.1,1 --delay-angle-csv " +
      angle.string() + " --delay-radius-csv " + radius.string());
  ASSERT_EQ(r.rc, 0) << r.out;
  std::map<std::string, double> delay;  // "model:depth:tlo" -> delay row
  std::stringstream ss(r.out);
  std::string line;
  int gsa_rows = 0;
  while (std::getline(ss, line)) {
    const auto v = nimbus::test::split_csv(line);
    if (v.size() == 9 && v[2] == "delay" && v[0] != "gsa")
      delay[v[0] + ":" + v[1] + ":" + v[3]] = std::stod(v[5]);
    if (v.size() == 9 && v[0] == "gsa" && v[2].rfind("delay", 0) == 0) ++gsa_rows;
  }
  EXPECT_EQ(gsa_rows, 2 * (4 + 2));  // 0..0.01, two bins, the tail; mean and variance; per depth
  ASSERT_EQ(delay.size(), 2u * 2u * 4u);
  for (const auto& [path, q, bins] :
       {std::tuple{angle, "delay_angle", 2}, std::tuple{radius, "delay_radius", 2}}) {
    const auto rows = read_rows(path);
    ASSERT_FALSE(rows.empty());
    EXPECT_EQ(rows[0].size(), 11u);
    EXPECT_EQ(rows[0][3], "tlo");
    // depths x time rows x (bins + outside), mc only
    EXPECT_EQ(rows.size(), 1u + 2u * 4u * (bins + 1u)) << q;
    std::map<std::string, double> sum;
    for (size_t i = 1; i < rows.size(); ++i) {
      EXPECT_EQ(rows[i][2], q);
      sum[rows[i][0] + ":" + rows[i][1] + ":" + rows[i][3]] += std::stod(rows[i][7]);
    }
    for (const auto& [key, v] : delay) {  // the same tallies, to the 9 digits printed
      if (key.rfind("mc:", 0) == 0) {
        EXPECT_NEAR(sum[key], v, 1e-8 * v + 1e-15) << q << " " << key;
      }
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(CliTime, BeamBadJointTablesExitWithCode2NamingTheArgument) {
  const auto dir = nimbus::test::cli_temp_dir("cli_time_test");
  const auto out = dir / "never.csv";
  const std::string beam = "beam --phase hg:0.9 --albedo 0.9 --photons 100 --depths 1 ";
  const struct {
    std::string args, named;
  } cases[] = {
      {"--delay-angle-csv " + out.string(), "--delay-angle-csv"},  // no --time-edges
      {"--time-edges 0,1 --delay-radius-csv " + (dir / "no" / "x.csv").string(), "--delay-radius-csv"},
      {"--time-edges 0,1 --delay-angle-csv -", "--delay-angle-csv"},
      {"--time-edges 0:1:50000 --delay-angle-csv " + out.string(), "--delay-angle-csv"},  // memory
      {"--time-edges 0,1 --models gsa,mfs --delay-radius-csv " + out.string(), "--delay-radius-csv"},
  };
  for (const auto& c : cases) {
    const CliRun r = run_cli(beam + c.args);
    EXPECT_EQ(r.rc, 2) << c.args << ": " << r.out;
    EXPECT_NE(r.out.find(c.named), std::string::npos) << c.args << ": " << r.out;
  }
  EXPECT_FALSE(std::filesystem::exists(out));
  std::filesystem::remove_all(dir);
}

const char* const kBadEdges[] = {"''", "2,1", "-1,1", "0:1:1e9", "5"};

TEST(CliTime, SlabBadTimeEdgesExitWithCode2NamingTheArgument) {
  const auto dir = nimbus::test::cli_temp_dir("cli_time_test");
  const auto out = dir / "never.csv";
  const std::string slab =
      "slab --mu-s 1 --mu-a 0 --g 0 --thickness 1 --photons 100 --time-csv " + out.string();
  for (const char* bad : kBadEdges) {
    const CliRun r = run_cli(slab + " --time-edges=" + bad);
    EXPECT_EQ(r.rc, 2) << bad << ": " << r.out;
    EXPECT_NE(r.out.find("--time-edges"), std::string::npos) << bad << ": " << r.out;
  }
  const CliRun r = run_cli(slab);  // --time-csv without --time-edges
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_FALSE(std::filesystem::exists(out));
  std::filesystem::remove_all(dir);
}

TEST(CliTime, BeamBadTimeEdgesExitWithCode2NamingTheArgument) {
  const std::string beam = "beam --phase hg:0.9 --albedo 0.9 --photons 100 --depths 1 --time-edges=";
  for (const char* bad : kBadEdges) {
    const CliRun b = run_cli(beam + bad);
    EXPECT_EQ(b.rc, 2) << bad << ": " << b.out;
    EXPECT_NE(b.out.find("--time-edges"), std::string::npos) << bad << ": " << b.out;
  }
  // More bins x depths than the tallies may hold.
  std::string depths = "0.1";
  for (int i = 2; i <= 100; ++i) depths += "," + std::to_string(0.1 * i);
  const CliRun m =
      run_cli("beam --phase hg:0.9 --albedo 0.9 --photons 100 --time-edges 0:1:100000 --depths " + depths);
  EXPECT_EQ(m.rc, 2) << m.out;
  EXPECT_NE(m.out.find("--time-edges"), std::string::npos) << m.out;
}

}  // namespace
