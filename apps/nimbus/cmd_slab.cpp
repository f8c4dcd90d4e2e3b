// nimbus slab: photon Monte Carlo of a pencil beam normally incident on a slab, MCML conventions
// (physical units: any consistent length unit).  Prints `name value stderr` lines for specular,
// diffuse_reflectance, transmittance (unscattered included), unscattered_transmittance and absorbed;
// --csv [FILE] adds angle- and radius-resolved reflectance and transmittance (to FILE or stdout):
//   side,quantity,lo,hi,value,stderr,bin_unit,value_unit   side = reflect|transmit, quantity = angular
//   (per sr of exit solid angle, bins of exit polar angle outside the slab, rad) or radial (per unit
//   area, bins of exit radius, length). docs/cli.md.
// --time-edges t0,t1,... or lo:hi:N adds time-resolved exits (to --time-csv FILE, or stdout):
//   tlo,thi,reflectance,reflectance_stderr,transmittance,transmittance_stderr
//   time = n * path length in the medium (c = 1 in vacuum), in the length unit of --thickness; values are
//   fractions of the source photons leaving in [tlo, thi) (divide by thi - tlo for a rate).  A row
//   0..t0 (if t0 > 0) and a row t_last..inf hold the rest, so the rows sum to the steady values.
#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "core/math.h"
#include "nimbus/error.h"
#include "transport/phase_spec.h"
#include "transport/photon_mc.h"
#include "transport/time_resolved.h"

namespace nimbus::cli {

namespace {

struct SlabArgs {
  double mu_s = -1.0, mu_a = -1.0, thickness = -1.0, n = 1.0, photons = 1e6;
  std::optional<double> g_given;  // --g G: hg:G
  std::string phase;              // --phase SPEC, as beam's
  uint64_t seed = 1;
  int angle_bins = 30, r_bins = 50;
  double r_max = 0.0;
  bool csv = false;
  std::string csv_path;
  std::string time_edges, time_csv;
  bool time_given = false;
};

// The time-resolved exits as CSV (see the top of this file).
std::string time_csv(const std::vector<double>& edges, const PhotonMcResult& r) {
  std::string csv = "tlo,thi,reflectance,reflectance_stderr,transmittance,transmittance_stderr\n";
  auto row = [&](double lo, double hi, const Estimate& R, const Estimate& T) {
    csv += fmt::format("{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n", lo, hi, R.value, R.err, T.value, T.err);
  };
  if (edges.front() > 0.0) row(0.0, edges.front(), r.reflect_time.before, r.transmit_time.before);
  for (size_t i = 0; i + 1 < edges.size(); ++i)
    row(edges[i], edges[i + 1], r.reflect_time.bins[i], r.transmit_time.bins[i]);
  row(edges.back(), std::numeric_limits<double>::infinity(), r.reflect_time.after, r.transmit_time.after);
  return csv;
}

int run_slab(const SlabArgs& a) {
  if (!a.csv_path.empty() && a.csv_path != "-") check_output_path(a.csv_path, "--csv");
  if (!a.time_csv.empty() && a.time_csv != "-") check_output_path(a.time_csv, "--time-csv");
  if (!a.time_csv.empty() && !a.time_given) throw Error("--time-csv needs --time-edges");
  if (!(a.mu_s >= 0.0) || !std::isfinite(a.mu_s))
    throw Error(fmt::format("--mu-s must be >= 0 (got {})", a.mu_s));
  if (!(a.mu_a >= 0.0) || !std::isfinite(a.mu_a))
    throw Error(fmt::format("--mu-a must be >= 0 (got {})", a.mu_a));
  // Each finite, their sum (the extinction) may still overflow: 1e308 + 1e308 made an infinite
  // sigma_t and a slab that reflected everything.
  if (!std::isfinite(a.mu_s + a.mu_a))
    throw Error(fmt::format("--mu-s + --mu-a must be finite (got {} + {})", a.mu_s, a.mu_a));
  if (a.g_given && !a.phase.empty()) throw Error("--g and --phase: give one (--g G is --phase hg:G)");
  if (!a.g_given && a.phase.empty()) throw Error("--phase (or --g) is required");
  if (a.g_given && !(*a.g_given > -1.0 && *a.g_given < 1.0))
    throw Error(fmt::format("--g must lie in (-1, 1) (got {})", *a.g_given));
  Phase phase = HgPhase{a.g_given.value_or(0.0)};
  if (!a.phase.empty()) {
    try {
      phase = parse_phase_spec(a.phase);
    } catch (const Error& e) {
      throw Error(fmt::format("--phase: {}", e.what()));
    }
  }
  const double g = phase_mean_cosine(phase);
  if (!(a.thickness > 0.0) || !std::isfinite(a.thickness))
    throw Error(fmt::format("--thickness must be > 0 (got {})", a.thickness));
  if (!(a.n >= 1.0) || !std::isfinite(a.n) || a.n > 10.0)
    throw Error(fmt::format("--n must lie in [1, 10] (got {})", a.n));
  if (!(a.photons >= 20.0) || a.photons > 1e12 || a.photons != std::floor(a.photons))
    throw Error("--photons must be a whole number >= 20");
  if (a.angle_bins < 1 || a.r_bins < 1) throw Error("--angle-bins and --r-bins must be >= 1");
  PhotonMcSettings s;
  s.sigma_s = a.mu_s;
  s.sigma_a = a.mu_a;
  s.phase = phase;
  s.thickness = a.thickness;
  s.n = a.n;
  s.photons = uint64_t(a.photons);
  s.seed = a.seed;
  s.batches = 20;
  if (a.time_given) s.time_edges = parse_time_edges("--time-edges", a.time_edges);
  for (int i = 0; i <= a.angle_bins; ++i) s.theta_edges.push_back(0.5 * kPi * i / a.angle_bins);
  const double transport = a.mu_a + a.mu_s * (1.0 - g);
  const double r_max =
      a.r_max > 0.0 ? a.r_max : 5.0 * std::max(a.thickness, transport > 0.0 ? 1.0 / transport : a.thickness);
  for (int i = 0; i <= a.r_bins; ++i) s.r_edges.push_back(r_max * i / a.r_bins);
  const PhotonMcResult r = run_photon_mc(s);

  std::string text;
  auto line = [&](const char* name, const Estimate& e) {
    text += fmt::format("{} {:.8g} {:.3g}\n", name, e.value, e.err);
  };
  line("specular", r.specular);
  line("diffuse_reflectance", r.diffuse_reflectance);
  line("transmittance", r.transmittance);
  line("unscattered_transmittance", r.unscattered_transmittance);
  line("absorbed", r.absorbed);
  std::fwrite(text.data(), 1, text.size(), stdout);
  if (a.time_given && !write_text(a.time_csv, time_csv(s.time_edges, r))) return kExitFailure;
  if (!a.csv) return kExitOk;

  std::string csv = "side,quantity,lo,hi,value,stderr,bin_unit,value_unit\n";
  auto rows = [&](const char* side, const char* q, const std::vector<double>& edges,
                  const std::vector<Estimate>& v) {
    const bool angular = std::string(q) == "angular";
    for (size_t i = 0; i < v.size(); ++i)
      csv += fmt::format("{},{},{:.9g},{:.9g},{:.9g},{:.9g},{},{}\n", side, q, edges[i], edges[i + 1],
                         v[i].value, v[i].err, angular ? "rad" : "length",
                         angular ? "1/sr per photon" : "1/length^2 per photon");
  };
  rows("reflect", "angular", s.theta_edges, r.reflect_angular);
  rows("reflect", "radial", s.r_edges, r.reflect_radial);
  rows("transmit", "angular", s.theta_edges, r.transmit_angular);
  rows("transmit", "radial", s.r_edges, r.transmit_radial);
  return write_text(a.csv_path, csv) ? kExitOk : kExitFailure;
}

}  // namespace

void add_slab_command(CLI::App& app, Action& action) {
  auto args = std::make_shared<SlabArgs>();
  auto* cmd = app.add_subcommand("slab",
                                 "Photon Monte Carlo of a pencil beam on a slab (MCML conventions, any phase "
                                 "function beam accepts, physical units)");
  cmd->add_option("--mu-s", args->mu_s, "Scattering coefficient [1/length]")->required();
  cmd->add_option("--mu-a", args->mu_a, "Absorption coefficient [1/length]")->required();
  cmd->add_option("--g", args->g_given, "Henyey-Greenstein asymmetry g (the same as --phase hg:G)");
  cmd->add_option(
      "--phase", args->phase,
      "Phase function, as beam's: iso, hg:G, dhg:G1,G2,W, gauss:THETA2, mie:NAME or mie:FILE.csv");
  cmd->add_option("--thickness", args->thickness, "Slab thickness [length]")->required();
  cmd->add_option("--n", args->n, "Refractive index of the slab against 1 outside (default 1)");
  cmd->add_option("--photons", args->photons, "Photons (default 1e6)");
  cmd->add_option("--seed", args->seed, "Random seed (default 1)");
  cmd->add_option("--angle-bins", args->angle_bins, "Exit-angle bins over [0, pi/2] for --csv (default 30)");
  cmd->add_option("--r-bins", args->r_bins, "Exit-radius bins for --csv (default 50)");
  cmd->add_option("--r-max", args->r_max,
                  "Largest exit radius for --csv (default 5 transport lengths or 5 D)");
  auto* csv = cmd->add_option("--csv", args->csv_path,
                              "Also write angle- and radius-resolved tallies (to FILE, or stdout)")
                  ->expected(0, 1);
  auto* te = cmd->add_option("--time-edges", args->time_edges,
                             "Time-bin edges t0,t1,... or lo:hi:N (time = n * path length, in the length "
                             "unit); writes time-resolved R and T");
  cmd->add_option("--time-csv", args->time_csv, "File for the --time-edges table (default stdout)");
  cmd->callback([args, csv, te, &action] {
    args->csv = csv->count() > 0;
    args->time_given = te->count() > 0;
    action = [args] { return run_slab(*args); };
  });
}

}  // namespace nimbus::cli
