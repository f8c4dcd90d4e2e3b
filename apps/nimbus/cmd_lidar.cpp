// nimbus lidar: a pulsed lidar (collimated source, co-located receiver disk with a field of view) looking
// into a homogeneous slab; received power against time (src/transport/lidar.h, docs/validation/lidar.md).
// Physical units as `slab` (any consistent length unit); time = n * path length, out and back (the clear
// gap of --distance included).
// CSV (docs/cli.md): model,tlo,thi,value,stderr,bin_unit,value_unit
//   model   mc (photon Monte Carlo with next-event estimation), mfs (the fused small-angle model),
//           single (the single-scatter lidar equation), mc_analog (one row 0..inf: the photons that leave
//           the top face into the disk within the FOV, an independent steady estimate; receiver radius > 0)
//   value   energy per unit receiver area per source photon arriving in [tlo, thi) [1/length^2 per
//           photon] (divide by thi - tlo for a rate); mc and mfs also give a row 0..t0 (if t0 > 0) and a
//           row t_last..inf, so their rows sum to the whole return.
#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "commands.h"
#include "core/math.h"
#include "nimbus/error.h"
#include "transport/lidar.h"
#include "transport/phase_spec.h"
#include "transport/time_resolved.h"

namespace nimbus::cli {

namespace {

struct LidarArgs {
  double mu_s = -1.0, thickness = -1.0, distance = 0.0, n = 1.0, photons = 1e6, fov = -1.0, r_rx = 0.0;
  std::optional<double> mu_a, albedo, g;
  std::string phase, time_edges, models = "mc,mfs,single", out;
  uint64_t seed = 1;
};

Phase lidar_phase(const LidarArgs& a) {
  if (a.g && !a.phase.empty()) throw Error("--g and --phase: give one (--g G is --phase hg:G)");
  if (!a.g && a.phase.empty()) throw Error("--phase (or --g) is required");
  if (a.g) {
    if (!(*a.g > -1.0 && *a.g < 1.0)) throw Error(fmt::format("--g must lie in (-1, 1) (got {})", *a.g));
    return HgPhase{*a.g};
  }
  try {
    return parse_phase_spec(a.phase);
  } catch (const Error& e) {
    throw Error(fmt::format("--phase: {}", e.what()));
  }
}

LidarSettings lidar_settings(const LidarArgs& a) {
  LidarSettings s;
  if (!(a.mu_s > 0.0) || !std::isfinite(a.mu_s))
    throw Error(fmt::format("--mu-s must be > 0 (got {})", a.mu_s));
  if (a.mu_a.has_value() == a.albedo.has_value()) throw Error("give one of --mu-a and --albedo");
  if (a.mu_a && (!(*a.mu_a >= 0.0) || !std::isfinite(*a.mu_a + a.mu_s)))
    throw Error(fmt::format("--mu-a must be >= 0 and finite (got {})", *a.mu_a));
  if (a.albedo && !(*a.albedo > 0.0 && *a.albedo <= 1.0))
    throw Error(fmt::format("--albedo must lie in (0, 1] (got {})", *a.albedo));
  s.sigma_s = a.mu_s;
  s.sigma_a = a.mu_a ? *a.mu_a : a.mu_s * (1.0 / *a.albedo - 1.0);
  s.phase = lidar_phase(a);
  if (!(a.thickness > 0.0) || !std::isfinite(a.thickness))
    throw Error(fmt::format("--thickness must be finite and > 0 (got {})", a.thickness));
  s.thickness = a.thickness;
  if (!(a.distance >= 0.0) || !std::isfinite(a.distance))
    throw Error(fmt::format("--distance must be finite and >= 0 (got {})", a.distance));
  s.distance = a.distance;
  if (!(a.n >= 1.0 && a.n <= 10.0)) throw Error(fmt::format("--n must lie in [1, 10] (got {})", a.n));
  s.n = a.n;
  if (!(a.fov > 0.0 && a.fov < 0.5 * kPi))
    throw Error(fmt::format("--fov (half-angle, rad) must lie in (0, pi/2) (got {})", a.fov));
  s.fov = a.fov;
  if (!(a.r_rx >= 0.0) || !std::isfinite(a.r_rx))
    throw Error(fmt::format("--receiver-radius must be finite and >= 0 (got {})", a.r_rx));
  s.r_rx = a.r_rx;
  if (!(a.photons >= 20.0) || a.photons > 1e12 || a.photons != std::floor(a.photons))
    throw Error("--photons must be a whole number >= 20");
  s.photons = uint64_t(a.photons);
  s.seed = a.seed;
  s.time_edges = parse_time_edges("--time-edges", a.time_edges);
  return s;
}

std::vector<std::string> lidar_models(const std::string& list) {
  std::vector<std::string> v;
  std::stringstream ss(list);
  std::string m;
  while (std::getline(ss, m, ','))
    if (!m.empty()) {
      if (m != "mc" && m != "mfs" && m != "single")
        throw Error(fmt::format("--models: unknown model '{}' (use mc, mfs, single)", m));
      v.push_back(m);
    }
  if (v.empty()) throw Error("--models: empty list");
  return v;
}

int run_lidar(const LidarArgs& a) {
  if (!a.out.empty() && a.out != "-") check_output_path(a.out, "--output");
  const LidarSettings s = lidar_settings(a);
  const std::vector<std::string> models = lidar_models(a.models);
  const std::vector<double>& e = s.time_edges;
  const double inf = std::numeric_limits<double>::infinity();
  std::string text = "model,tlo,thi,value,stderr,bin_unit,value_unit\n";
  auto row = [&](const std::string& m, double lo, double hi, double v, double err) {
    text += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},length,1/length^2 per photon\n", m, lo, hi, v, err);
  };
  for (const std::string& m : models) {
    if (m == "mc") {
      const LidarMcResult r = run_lidar_mc(s);
      if (e.front() > 0.0) row(m, 0.0, e.front(), r.received.before.value, r.received.before.err);
      for (size_t i = 0; i + 1 < e.size(); ++i)
        row(m, e[i], e[i + 1], r.received.bins[i].value, r.received.bins[i].err);
      row(m, e.back(), inf, r.received.after.value, r.received.after.err);
      if (s.r_rx > 0.0) row("mc_analog", 0.0, inf, r.analog.value, r.analog.err);
    } else if (m == "mfs") {
      const LidarModelResult r = lidar_mfs(s);
      if (e.front() > 0.0) row(m, 0.0, e.front(), r.before, 0.0);
      for (size_t i = 0; i + 1 < e.size(); ++i) row(m, e[i], e[i + 1], r.bins[i], 0.0);
      row(m, e.back(), inf, r.after, 0.0);
    } else {
      const std::vector<double> v = lidar_single_scatter(s);
      for (size_t i = 0; i + 1 < e.size(); ++i) row(m, e[i], e[i + 1], v[i], 0.0);
    }
  }
  return write_text(a.out, text) ? kExitOk : kExitFailure;
}

}  // namespace

void add_lidar_command(CLI::App& app, Action& action) {
  auto a = std::make_shared<LidarArgs>();
  auto* cmd = app.add_subcommand("lidar",
                                 "Pulsed lidar into a slab: received power against time, photon Monte Carlo "
                                 "against the fused small-angle model and the single-scatter equation");
  cmd->add_option("--mu-s", a->mu_s, "Scattering coefficient [1/length]")->required();
  cmd->add_option("--mu-a", a->mu_a, "Absorption coefficient [1/length] (or --albedo)");
  cmd->add_option("--albedo", a->albedo, "Single-scattering albedo in (0, 1] (or --mu-a)");
  cmd->add_option("--g", a->g, "Henyey-Greenstein asymmetry g (the same as --phase hg:G)");
  cmd->add_option("--phase", a->phase,
                  "Phase function, as slab's: iso, hg:G, dhg:G1,G2,W, gauss:THETA2, mie:NAME|FILE");
  cmd->add_option("--thickness", a->thickness, "Slab thickness [length]")->required();
  cmd->add_option("--distance", a->distance,
                  "From the lidar to the slab's near face [length] (a clear gap; default 0)");
  cmd->add_option("--n", a->n,
                  "Refractive index: time = n * path length, gap included (boundaries matched; default 1)");
  cmd->add_option("--fov", a->fov, "Receiver field of view, half-angle [rad]")->required();
  cmd->add_option("--receiver-radius", a->r_rx, "Receiver disk radius [length] (default 0: a point)");
  cmd->add_option("--time-edges", a->time_edges, "Time-bin edges t0,t1,... or lo:hi:N [length]")->required();
  cmd->add_option("--models", a->models, "Comma-separated subset of mc,mfs,single (default all)");
  cmd->add_option("--photons", a->photons, "Monte Carlo photons (default 1e6)");
  cmd->add_option("--seed", a->seed, "Random seed (default 1)");
  cmd->add_option("-o,--output", a->out, "Output CSV (default stdout)");
  cmd->callback([a, &action] { action = [a] { return run_lidar(*a); }; });
}

}  // namespace nimbus::cli
