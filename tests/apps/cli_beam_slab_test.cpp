// `nimbus beam` and `nimbus slab` run as a user would: the CSV layout and lines they promise, atomic
// output, and exit code 2 with a clear message on bad arguments.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli.h"

namespace {

using nimbus::test::CliRun;
using nimbus::test::run_cli;

TEST(CliBeam, WritesTheDocumentedCsv) {
  const auto dir = nimbus::test::cli_temp_dir("cli_test");
  const auto out = dir / "beam.csv";
  const CliRun r = run_cli(
      "beam --phase hg:0.9 --albedo 0.99 --depths 1,3 --photons 2000 --theta-edges 0,0.01,0.1,1,3.14159 "
      "--r-edges 0,0.1,1,10 -o " +
      out.string());
  ASSERT_EQ(r.rc, 0) << r.out;
  std::ifstream in(out);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "model,depth,quantity,lo,hi,value,stderr,bin_unit,value_unit");
  std::map<std::string, int> rows_per_model;
  std::set<std::string> quantities;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string model, depth, quantity, lo, hi, value, err;
    std::getline(ss, model, ',');
    std::getline(ss, depth, ',');
    std::getline(ss, quantity, ',');
    std::getline(ss, lo, ',');
    std::getline(ss, hi, ',');
    std::getline(ss, value, ',');
    std::getline(ss, err, ',');
    ++rows_per_model[model];
    quantities.insert(quantity);
    EXPECT_TRUE(std::isfinite(std::stod(value))) << line;
    if (quantity == "unscattered") {
      EXPECT_EQ(std::stod(lo), 0.0);
      EXPECT_EQ(std::stod(hi), 0.0);
      if (model != "mc") {
        EXPECT_NEAR(std::stod(value), std::exp(-std::stod(depth) / 0.99), 1e-8);
      }
    }
  }
  // Every model by default; per depth 4 angular + 3 radial + 1 unscattered rows.
  for (const char* m : {"mc", "dolin", "tes87", "mfs", "gsa"}) EXPECT_EQ(rows_per_model[m], 2 * 8) << m;
  EXPECT_EQ(quantities, (std::set<std::string>{"angular", "radial", "unscattered"}));
  // No temporary file left beside the output.
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 1);
  std::filesystem::remove_all(dir);
}

TEST(CliBeam, ModelsSubsetSlabAndSeed) {
  const CliRun a = run_cli(
      "beam --phase gauss:0.01 --albedo 0.9 --depths 1 --geometry slab:2 --n 1.33 --photons 500 "
      "--models mc --theta-edges 0,0.1,3.14159 --r-edges 0,1 --seed 7");
  const CliRun b = run_cli(
      "beam --phase gauss:0.01 --albedo 0.9 --depths 1 --geometry slab:2 --n 1.33 --photons 500 "
      "--models mc --theta-edges 0,0.1,3.14159 --r-edges 0,1 --seed 7");
  ASSERT_EQ(a.rc, 0) << a.out;
  EXPECT_EQ(a.out, b.out);
  EXPECT_EQ(a.out.find("gsa"), std::string::npos);
  EXPECT_NE(a.out.find("mc,1,angular,0,0.1,"), std::string::npos) << a.out;
}

TEST(CliBeam, BadArgumentsExitWithCode2AndAMessage) {
  const std::string base = " --depths 1,3 --photons 100";
  const std::pair<std::string, std::string> cases[] = {
      {"beam --phase hg:1.5 --albedo 0.9" + base, "asymmetry"},
      {"beam --phase foo:1 --albedo 0.9" + base, "unknown type"},
      {"beam --phase hg:abc --albedo 0.9" + base, "not a number"},
      {"beam --phase dhg:0.9,0.1 --albedo 0.9" + base, "expected 3"},
      {"beam --phase mie:no_such_table --albedo 0.9" + base, "cannot open"},
      {"beam --phase mie:../x --albedo 0.9" + base, "cannot open"},  // a path: that file
      {"beam --phase mie:a\\ b --albedo 0.9" + base, "table name"},
      {"beam --phase hg:0.9 --albedo -0.1" + base, "albedo"},
      {"beam --phase hg:0.9 --albedo 1.5" + base, "albedo"},
      {"beam --phase hg:0.9 --albedo 0.9 --depths 3,1", "increase"},
      {"beam --phase hg:0.9 --albedo 0.9 --depths 1,x", "not a number"},
      {"beam --phase hg:0.9 --albedo 0.9 --depths 1 --models mc,foo", "unknown model"},
      {"beam --phase hg:0.9 --albedo 0.9 --depths 1 --geometry slab:0.5", "inside the slab"},
      {"beam --phase hg:0.9 --albedo 0.9 --depths 1 --geometry cube", "geometry"},
      {"beam --phase hg:0.9 --albedo 0.9 --depths 1 --n 1.33", "slab"},
      {"beam --phase hg:0.9 --albedo 0.9 --depths 1 --theta-edges 0.2,0.1", "increase"},
      {"beam --albedo 0.9 --depths 1", "phase"},
      {"slab --mu-s 10 --mu-a 1 --g 1.2 --thickness 1", "--g"},
      {"slab --mu-s -10 --mu-a 1 --g 0.9 --thickness 1", "--mu-s"},
      {"slab --mu-s 10 --mu-a 1 --g 0.9 --thickness 0", "--thickness"},
      {"slab --mu-s 10 --mu-a 1 --g 0.9 --thickness 1 --n 0.5", "--n"},
  };
  for (const auto& [args, needle] : cases) {
    const CliRun r = run_cli(args);
    EXPECT_EQ(r.rc, 2) << args << "\n" << r.out;
    EXPECT_NE(r.out.find(needle), std::string::npos) << args << "\n" << r.out;
  }
}

TEST(CliSlab, PrintsTheFiveTotalsThatBalance) {
  const CliRun r = run_cli("slab --mu-s 100 --mu-a 0.1 --g 0.9 --thickness 0.1 --n 1.33 --photons 5000");
  ASSERT_EQ(r.rc, 0) << r.out;
  std::stringstream ss(r.out);
  std::map<std::string, double> v;
  std::string name;
  double value, err;
  while (ss >> name >> value >> err) v[name] = value;
  ASSERT_EQ(v.size(), 5u) << r.out;
  EXPECT_NEAR(v["specular"], std::pow(0.33 / 2.33, 2), 1e-7);
  EXPECT_NEAR(v["specular"] + v["diffuse_reflectance"] + v["transmittance"] + v["absorbed"], 1.0, 1e-3);
  EXPECT_LE(v["unscattered_transmittance"], v["transmittance"]);
  const CliRun c = run_cli(
      "slab --mu-s 100 --mu-a 0.1 --g 0.9 --thickness 0.1 --photons 500 --csv --angle-bins 3 --r-bins 2");
  ASSERT_EQ(c.rc, 0) << c.out;
  EXPECT_NE(c.out.find("side,quantity,lo,hi,value,stderr,bin_unit,value_unit"), std::string::npos);
  EXPECT_NE(c.out.find("transmit,radial,"), std::string::npos);
}

TEST(CliSlab, TakesEveryPhaseFunctionBeamTakes) {
  // --g G is --phase hg:G: the same photons, the same numbers.
  const std::string slab = "slab --mu-s 100 --mu-a 0.1 --thickness 0.1 --photons 400 ";
  const CliRun g = run_cli(slab + "--g 0.9"), hg = run_cli(slab + "--phase hg:0.9");
  ASSERT_EQ(g.rc, 0) << g.out;
  EXPECT_EQ(g.out, hg.out);
  // The other kinds run and conserve energy; a table by path (mie:FILE.csv) as well as by name.
  const auto table = nimbus::test::cli_temp_dir("cli_test") / "my_mie.csv";
  std::filesystem::copy_file(
      std::filesystem::path(NIMBUS_SOURCE_DIR) / "data" / "phase" / "cloud_mie_550nm.csv", table,
      std::filesystem::copy_options::overwrite_existing);
  for (const std::string& phase : std::vector<std::string>{"iso", "dhg:0.9,-0.3,0.8", "gauss:0.01",
                                                           "mie:cloud_mie_550nm", "mie:" + table.string()}) {
    const CliRun r = run_cli(slab + "--phase " + phase);
    ASSERT_EQ(r.rc, 0) << phase << ": " << r.out;
    std::stringstream ss(r.out);
    std::map<std::string, double> v;
    std::string name;
    double value, err;
    while (ss >> name >> value >> err) v[name] = value;
    EXPECT_NEAR(v["specular"] + v["diffuse_reflectance"] + v["transmittance"] + v["absorbed"], 1.0, 1e-6)
        << phase;
  }
  EXPECT_EQ(
      run_cli("beam --phase mie:" + table.string() + " --albedo 0.9 --depths 1 --photons 200 --models dolin")
          .rc,
      0);
  // Both, neither, or a bad spec: exit 2 naming the option.
  for (const std::string bad :
       {"--g 0.5 --phase iso", "", "--phase hg:2", "--phase mie:/nonexistent/t.csv"}) {
    const CliRun r = run_cli(slab + bad);
    EXPECT_EQ(r.rc, 2) << bad << ": " << r.out;
    EXPECT_NE(r.out.find("--"), std::string::npos) << r.out;
  }
}

}  // namespace
