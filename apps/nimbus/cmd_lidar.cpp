// nimbus lidar: a pulsed lidar (collimated source, co-located receiver disk with a field of view) looking
// into a homogeneous slab (src/transport/lidar.h) or, with --scene, into a scene's media from --origin
// along --dir (src/integrators/lidar_scene.h: mc and single only); received power against time
// (docs/validation/lidar.md).
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
#include <functional>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cmd_lidar_scene.h"
#include "commands.h"
#include "core/math.h"
#include "nimbus/error.h"
#include "transport/lidar.h"
#include "transport/phase_spec.h"
#include "transport/time_resolved.h"

namespace nimbus::cli {

namespace {

struct LidarArgs {
  double n = 1.0, photons = 1e6, fov = -1.0, r_rx = 0.0;
  std::optional<double> mu_s, thickness, distance, mu_a, albedo, g;
  std::string phase, time_edges, models, out;          // models: empty for the default
  std::string scene, origin = "0,0,0", dir = "0,0,1";  // --scene mode
  std::string surface = "matched";
  int channel = 1;
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

// The options both lidars share (index, receiver, photons, time bins), checked.
template <typename Settings>
void receiver_settings(const LidarArgs& a, Settings& s) {
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
}

LidarSettings lidar_settings(const LidarArgs& a) {
  LidarSettings s;
  if (!a.mu_s) throw Error("--mu-s is required (or --scene FILE)");
  if (!a.thickness) throw Error("--thickness is required (or --scene FILE)");
  if (!(*a.mu_s > 0.0) || !std::isfinite(*a.mu_s))
    throw Error(fmt::format("--mu-s must be > 0 (got {})", *a.mu_s));
  if (a.mu_a.has_value() == a.albedo.has_value()) throw Error("give one of --mu-a and --albedo");
  if (a.mu_a && (!(*a.mu_a >= 0.0) || !std::isfinite(*a.mu_a + *a.mu_s)))
    throw Error(fmt::format("--mu-a must be >= 0 and finite (got {})", *a.mu_a));
  if (a.albedo && !(*a.albedo > 0.0 && *a.albedo <= 1.0))
    throw Error(fmt::format("--albedo must lie in (0, 1] (got {})", *a.albedo));
  s.sigma_s = *a.mu_s;
  s.sigma_a = a.mu_a ? *a.mu_a : *a.mu_s * (1.0 / *a.albedo - 1.0);
  s.phase = lidar_phase(a);
  if (!(*a.thickness > 0.0) || !std::isfinite(*a.thickness))
    throw Error(fmt::format("--thickness must be finite and > 0 (got {})", *a.thickness));
  s.thickness = *a.thickness;
  s.distance = a.distance.value_or(0.0);
  if (a.surface != "matched" && a.surface != "fresnel")
    throw Error(fmt::format("--surface must be matched or fresnel (got '{}')", a.surface));
  s.fresnel = a.surface == "fresnel";
  if (s.fresnel && !(s.distance > 0.0)) throw Error("--surface fresnel needs --distance > 0 (the air gap)");
  if (!(s.distance >= 0.0) || !std::isfinite(s.distance))
    throw Error(fmt::format("--distance must be finite and >= 0 (got {})", s.distance));
  receiver_settings(a, s);
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

// --scene: the checked options for cmd_lidar_scene.cpp.
SceneLidarRequest scene_lidar_request(const LidarArgs& a, const std::vector<std::string>& models) {
  if (a.surface != "matched") throw Error("--surface: not available with --scene (a slab's top face)");
  if (a.mu_s || a.mu_a || a.albedo || a.g || !a.phase.empty() || a.thickness || a.distance)
    throw Error(
        "--scene: the scene gives the medium; leave out --mu-s, --mu-a, --albedo, --g, --phase, "
        "--thickness and --distance");
  for (const std::string& m : models)
    if (m == "mfs") throw Error("--models: mfs is not available with --scene (use mc, single)");
  SceneLidarRequest r;
  r.scene = a.scene;
  r.origin = a.origin;
  r.dir = a.dir;
  r.channel = a.channel;
  r.models = models;
  receiver_settings(a, r);
  return r;
}

int run_lidar(const LidarArgs& a) {
  if (!a.out.empty() && a.out != "-") check_output_path(a.out, "--output");
  std::string text = "model,tlo,thi,value,stderr,bin_unit,value_unit\n";
  auto row = [&](const std::string& m, double lo, double hi, double v, double err) {
    text += fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},length,1/length^2 per photon\n", m, lo, hi, v, err);
  };
  const bool plain = a.scene.empty() && a.surface == "matched";
  const std::vector<std::string> models = lidar_models(!a.models.empty() ? a.models
                                                       : plain           ? "mc,mfs,single"
                                                                         : "mc,single");
  if (!a.scene.empty()) {
    scene_lidar_rows(scene_lidar_request(a, models), row);
    return write_text(a.out, text) ? kExitOk : kExitFailure;
  }
  if (a.origin != "0,0,0" || a.dir != "0,0,1" || a.channel != 1)
    throw Error("--origin, --dir and --channel need --scene");
  if (a.surface == "fresnel")
    for (const std::string& m : models)
      if (m == "mfs")
        throw Error("--models: mfs has no Fresnel surface (use mc, single with --surface fresnel)");
  const LidarSettings s = lidar_settings(a);
  const std::vector<double>& e = s.time_edges;
  const double inf = std::numeric_limits<double>::infinity();
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
  if (s.fresnel) row("surface", 2.0 * s.distance, 2.0 * s.distance, lidar_surface_return(s), 0.0);
  return write_text(a.out, text) ? kExitOk : kExitFailure;
}

}  // namespace

void add_lidar_command(CLI::App& app, Action& action) {
  auto a = std::make_shared<LidarArgs>();
  auto* cmd = app.add_subcommand(
      "lidar",
      "Pulsed lidar into a slab or a scene's media: received power against time, photon Monte Carlo "
      "against the fused small-angle model and the single-scatter equation");
  cmd->add_option("--mu-s", a->mu_s, "Scattering coefficient [1/length] (slab)");
  cmd->add_option("--mu-a", a->mu_a, "Absorption coefficient [1/length] (or --albedo)");
  cmd->add_option("--albedo", a->albedo, "Single-scattering albedo in (0, 1] (or --mu-a)");
  cmd->add_option("--g", a->g, "Henyey-Greenstein asymmetry g (the same as --phase hg:G)");
  cmd->add_option(
      "--phase", a->phase,
      "Phase function, as slab's: iso, hg:G, dhg:G1,G2,W, gauss:THETA2, mie:NAME|FILE, ff:N,MU, ffb:B");
  cmd->add_option("--thickness", a->thickness, "Slab thickness [length] (slab)");
  cmd->add_option("--distance", a->distance,
                  "From the lidar to the slab's near face [length] (a clear gap; default 0)");
  cmd->add_option("--n", a->n,
                  "Refractive index: time = n * path length, gap included (boundaries matched; default 1)");
  cmd->add_option("--fov", a->fov, "Receiver field of view, half-angle [rad]")->required();
  cmd->add_option("--receiver-radius", a->r_rx, "Receiver disk radius [length] (default 0: a point)");
  cmd->add_option("--time-edges", a->time_edges, "Time-bin edges t0,t1,... or lo:hi:N [length]")->required();
  cmd->add_option("--surface", a->surface,
                  "The slab's top face: matched (default: n only scales time) or fresnel (air gap, a water "
                  "surface of index n that reflects and refracts)");
  cmd->add_option("--scene", a->scene, "Scene file: the lidar looks into its media instead of a slab");
  cmd->add_option("--origin", a->origin, "With --scene: the lidar's position x,y,z (default 0,0,0)");
  cmd->add_option("--dir", a->dir, "With --scene: the direction it looks, x,y,z (default 0,0,1)");
  cmd->add_option("--channel", a->channel,
                  "With --scene: the colour channel of the media, 0, 1 or 2 (default 1)");
  cmd->add_option("--models", a->models,
                  "Comma-separated subset of mc,mfs,single (default all; mc,single with --scene)");
  cmd->add_option("--photons", a->photons, "Monte Carlo photons (default 1e6)");
  cmd->add_option("--seed", a->seed, "Random seed (default 1)");
  cmd->add_option("-o,--output", a->out, "Output CSV (default stdout)");
  cmd->callback([a, &action] { action = [a] { return run_lidar(*a); }; });
}

}  // namespace nimbus::cli
