// `nimbus lidar` run as a user would: the CSV it promises (rows that sum to the whole return, the
// single-scatter rows equal to the mfs model's limit at small depth) and exit code 2 naming the argument
// on bad input, with nothing written.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli.h"

namespace {

using nimbus::test::CliRun;
using nimbus::test::run_cli;

const std::string kArgs =
    "lidar --mu-s 1 --albedo 0.9 --phase hg:0.9 --thickness 2 --distance 1 --fov 0.05 --receiver-radius 0.1 "
    "--photons 20000 --time-edges 2:6:8";

TEST(CliLidar, WritesTheCsvItPromises) {
  const auto out = nimbus::test::cli_temp_dir("cli_lidar_test") / "lidar.csv";
  const CliRun r = run_cli(kArgs + " -o " + out.string());
  ASSERT_EQ(r.rc, 0) << r.out;
  std::ifstream in(out);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "model,tlo,thi,value,stderr,bin_unit,value_unit");
  std::map<std::string, std::vector<std::vector<std::string>>> rows;
  while (std::getline(in, line)) {
    const auto v = nimbus::test::split_csv(line);
    ASSERT_EQ(v.size(), 7u) << line;
    EXPECT_EQ(v[5], "length");
    EXPECT_EQ(v[6], "1/length^2 per photon");
    rows[v[0]].push_back(v);
  }
  ASSERT_EQ(rows["mc"].size(), 10u);  // 0..2, eight bins, 6..inf
  ASSERT_EQ(rows["mfs"].size(), 10u);
  ASSERT_EQ(rows["single"].size(), 8u);
  ASSERT_EQ(rows["mc_analog"].size(), 1u);
  EXPECT_EQ(std::stod(rows["mc"].front()[3]), 0.0);  // the clear gap: nothing before 2 d
  EXPECT_TRUE(std::isinf(std::stod(rows["mc"].back()[2])));
  // Every model's bins hold at least the single-scatter return (mfs) or about it (mc, within noise).
  for (int i = 0; i < 8; ++i) {
    const double ss = std::stod(rows["single"][i][3]);
    EXPECT_GE(std::stod(rows["mfs"][i + 1][3]), ss * (1.0 - 1e-9));
    EXPECT_GT(std::stod(rows["mc"][i + 1][3]) + 5.0 * std::stod(rows["mc"][i + 1][4]), ss);
  }
}

// Each case exits 2, names `named` and writes nothing.
void expect_refused(const std::vector<std::pair<std::string, std::string>>& cases) {
  const auto out = nimbus::test::cli_temp_dir("cli_lidar_test") / "bad.csv";
  const std::string base =
      "lidar --mu-s 1 --albedo 0.9 --g 0.9 --thickness 2 --photons 100 -o " + out.string() + " ";
  for (const auto& [args, named] : cases) {
    const CliRun r = run_cli(base + args);
    EXPECT_EQ(r.rc, 2) << args << "\n" << r.out;
    EXPECT_NE(r.out.find(named), std::string::npos) << args << "\n" << r.out;
    EXPECT_FALSE(std::filesystem::exists(out)) << args;
  }
}

TEST(CliLidar, BadTimeEdgesExitTwoNamingTheArgument) {
  expect_refused({
      {"--fov 0.01 --time-edges ''", "--time-edges"},
      {"--fov 0.01 --time-edges 3,2", "--time-edges"},
      {"--fov 0.01 --time-edges -1,2", "--time-edges"},
  });
}

TEST(CliLidar, BadGeometryExitsTwoNamingTheArgument) {
  expect_refused({
      {"--fov 0 --time-edges 1,2", "--fov"},
      {"--fov 2 --time-edges 1,2", "--fov"},
      {"--fov 0.01 --receiver-radius -1 --time-edges 1,2", "--receiver-radius"},
      {"--fov 0.01 --distance -1 --time-edges 1,2", "--distance"},
  });
}

TEST(CliLidar, BadMediumOrModelsExitTwoAndTheOutputIsCheckedFirst) {
  expect_refused({
      {"--fov 0.01 --mu-a 0.1 --time-edges 1,2", "--albedo"},
      {"--fov 0.01 --models mc,foo --time-edges 1,2", "--models"},
      {"--fov 0.01 --time-edges 1,2 --surface glass", "--surface"},
      {"--fov 0.01 --time-edges 1,2 --surface fresnel", "--distance"},
      {"--fov 0.01 --time-edges 1,2 --surface fresnel --distance 1 --models mfs", "--models"},
  });
  // The output path is checked before any work (a billion photons would take hours).
  const CliRun r = run_cli(
      "lidar --mu-s 1 --albedo 0.9 --g 0.9 --thickness 2 --fov 0.01 --time-edges 1,2 --photons 1e9 -o "
      "/nonexistent/dir/x.csv");
  EXPECT_EQ(r.rc, 2) << r.out;
  EXPECT_NE(r.out.find("--output"), std::string::npos) << r.out;
}

// A wide box as a scene (the lidar ignores the camera and the light).
std::filesystem::path box_scene(const std::string& name, const std::string& sigma_s) {
  const auto file = nimbus::test::cli_temp_dir("cli_lidar_test") / name;
  std::ofstream(file) << R"({"camera": {"position": [0, -5, 0], "look_at": [0, 0, 0], "up": [0, 0, 1],
      "fov_y_deg": 30, "width": 8, "height": 8},
    "media": [{"shape": {"type": "box", "min": [-50, -50, 1], "max": [50, 50, 3]}, "sigma_s": )"
                      << sigma_s
                      << R"(, "sigma_a": 0.1, "phase": {"type": "fournier_forand", "n": 1.1, "mu": 3.5835}}],
    "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": 1}]})";
  return file;
}

TEST(CliLidar, SceneWritesMcAndSingleRows) {
  const auto out = nimbus::test::cli_temp_dir("cli_lidar_test") / "scene_lidar.csv";
  const CliRun r = run_cli("lidar --scene " + box_scene("box.json", "1").string() +
                           " --origin 0,0,0 --dir 0,0,2 --fov 0.05 --receiver-radius 0.1 --photons 4000 "
                           "--time-edges 2:6:8 --models mc,single -o " +
                           out.string());
  ASSERT_EQ(r.rc, 0) << r.out;
  std::ifstream in(out);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "model,tlo,thi,value,stderr,bin_unit,value_unit");
  std::map<std::string, std::vector<std::vector<std::string>>> rows;
  while (std::getline(in, line))
    rows[nimbus::test::split_csv(line)[0]].push_back(nimbus::test::split_csv(line));
  ASSERT_EQ(rows["mc"].size(), 10u);  // 0..2, eight bins, 6..inf
  ASSERT_EQ(rows["single"].size(), 8u);
  EXPECT_EQ(std::stod(rows["mc"].front()[3]), 0.0);  // nothing before 2 x the clear gap
  for (int i = 0; i < 8; ++i) EXPECT_GT(std::stod(rows["single"][i][3]), 0.0);
}

TEST(CliLidar, BadSceneInputExitsTwoNamingFileAndField) {
  const auto out = nimbus::test::cli_temp_dir("cli_lidar_test") / "bad_scene.csv";
  const std::string good = box_scene("good.json", "1").string(), bad = box_scene("bad.json", "-1").string();
  const std::string tail = " --fov 0.05 --time-edges 2:6:8 --photons 100 -o " + out.string();
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"--scene " + bad, {"bad.json", "/media/0/sigma_s"}},
      {"--scene " + (nimbus::test::cli_temp_dir("cli_lidar_test") / "missing.json").string(),
       {"missing.json"}},
      {"--scene " + good + " --mu-s 1", {"--mu-s"}},
      {"--scene " + good + " --models mfs", {"--models"}},
      {"--scene " + good + " --dir 0,0,0", {"--dir"}},
      {"--scene " + good + " --dir 1,2", {"--dir"}},
      {"--scene " + good + " --origin 1,2,x", {"--origin"}},
      {"--scene " + good + " --channel 3", {"--channel"}},
      {"--scene " + good + " --surface fresnel", {"--surface"}},
      {"--mu-s 1 --albedo 0.9 --g 0.9 --thickness 2 --origin 1,1,1", {"--origin"}},
      {"--albedo 0.9 --g 0.9 --thickness 2", {"--mu-s"}},
  };
  for (const auto& [args, named] : cases) {
    const CliRun r = run_cli("lidar " + args + tail);
    EXPECT_EQ(r.rc, 2) << args << "\n" << r.out;
    for (const std::string& n : named) EXPECT_NE(r.out.find(n), std::string::npos) << args << "\n" << r.out;
    EXPECT_FALSE(std::filesystem::exists(out)) << args;
  }
}

TEST(CliLidar, FresnelSurfaceRowAndDefaultModels) {
  const auto out = nimbus::test::cli_temp_dir("cli_lidar_test") / "fresnel.csv";
  const CliRun r = run_cli(
      "lidar --mu-s 1 --albedo 0.9 --g 0.9 --thickness 2 --distance 1 --n 1.33 --surface fresnel --fov 0.05 "
      "--receiver-radius 0.1 --photons 2000 --time-edges 2:6:4 -o " +
      out.string());
  ASSERT_EQ(r.rc, 0) << r.out;
  std::ifstream in(out);
  std::string line;
  std::map<std::string, std::vector<std::vector<std::string>>> rows;
  while (std::getline(in, line))
    rows[nimbus::test::split_csv(line)[0]].push_back(nimbus::test::split_csv(line));
  EXPECT_EQ(rows["mc"].size(), 6u);  // 0..2, four bins, 6..inf
  EXPECT_EQ(rows["single"].size(), 4u);
  EXPECT_EQ(rows["mfs"].size(), 0u);
  ASSERT_EQ(rows["surface"].size(), 1u);
  EXPECT_EQ(rows["surface"][0][1], "2");  // at twice the gap
  EXPECT_NEAR(std::stod(rows["surface"][0][3]), std::pow(0.33 / 2.33, 2) / (M_PI * 0.01), 1e-7);
}

}  // namespace
