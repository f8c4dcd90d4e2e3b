// nimbus beam: a pencil beam into a forward-scattering medium, photon Monte Carlo against every
// propagator (Dolin, Tessendorf 87/88, the corrected MFS kernel, the generalised small-angle one),
// tallied at planes of given optical depth.  Lengths in scattering mean free paths (b = 1).
//
// CSV columns (docs/cli.md): model,depth,quantity,lo,hi,value,stderr,bin_unit,value_unit; depth in mfp,
// quantity
//   angular     bins [lo, hi) of polar angle [rad]; plane-integrated scattered radiance [1/sr per photon]
//   radial      bins of radius [mfp]; forward scattered flux per unit area [1/mfp^2 per photon]
//   unscattered lo = hi = 0; unscattered flux through the plane [per photon]
// With --time-edges (t0,t1,... or lo:hi:N, in mfp; time = n * path length):
//   delay          bins of the delay n (s - z) [mfp] of scattered light crossing the plane forward
//                  (weight per bin per source photon; rows 0..t0 if t0 > 0 and t_last..inf hold the rest);
//                  models mc, mfs (its closed form) and gsa (a moment-matched gamma law, gsa_delay.h)
//   delay_mean     lo = hi = 0; mean delay of that light [mfp]
//   delay_variance lo = hi = 0; its variance [mfp^2]
//   (model mc_fwd: delay, delay_mean, delay_variance of the photons that never travelled backward)
// --delay-angle-csv FILE / --delay-radius-csv FILE (need --time-edges): the joint tables of mc,
//   model,depth,quantity,tlo,thi,lo,hi,value,stderr,bin_unit,value_unit (beam_table.h BeamJointRow)
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "commands.h"
#include "nimbus/error.h"
#include "transport/beam_table.h"
#include "transport/phase_spec.h"
#include "transport/time_resolved.h"

namespace nimbus::cli {

namespace {

struct BeamArgs {
  std::string phase, geometry = "infinite", models, theta_edges, r_edges, out, time_edges;
  std::string angle_csv, radius_csv;  // joint delay tables
  bool time_given = false;
  double albedo = -1.0, n = 1.0, photons = 1e6;
  std::string depths;
  uint64_t seed = 1;
  bool n_given = false;
};

std::vector<std::string> split_names(const std::string& list) {
  std::vector<std::string> v;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) v.push_back(item);
  return v;
}

// The joint delay x angle / delay x radius options: they need --time-edges, a writable file, and
// (time bins + 4) x (angle or radius bins + 2) x (depths + 2) tallies of at most about 4e6.
void check_joint_options(const BeamArgs& a, BeamSettings& s) {
  const std::vector<double> te = s.theta_edges.empty() ? default_theta_edges() : s.theta_edges;
  const std::vector<double> re = s.r_edges.empty() ? default_r_edges() : s.r_edges;
  auto check = [&](const std::string& path, const char* option, const std::vector<double>& edges) {
    if (path.empty()) return false;
    if (path == "-") throw Error(fmt::format("{} needs a file (stdout carries the main table)", option));
    check_output_path(path, option);
    if (!a.time_given) throw Error(fmt::format("{} needs --time-edges", option));
    const double slots =
        double(s.time_edges.size() + 4) * double(edges.size() + 2) * double(s.depths.size() + 2);
    if (slots > 4e6)
      throw Error(
          fmt::format("{}: {} delay bins x {} bins x {} depths need more memory than allowed (at most "
                      "about 4e6; fewer --time-edges, edges or depths)",
                      option, s.time_edges.size() - 1, edges.size() - 1, s.depths.size()));
    return true;
  };
  s.joint_angle = check(a.angle_csv, "--delay-angle-csv", te);
  s.joint_radius = check(a.radius_csv, "--delay-radius-csv", re);
}

bool write_joint_tables(const BeamArgs& a, const std::vector<BeamJointRow>& joint) {
  for (const auto& [path, q, unit] :
       {std::tuple{a.angle_csv, "delay_angle", "rad"}, std::tuple{a.radius_csv, "delay_radius", "mfp"}}) {
    if (path.empty()) continue;
    std::string text = "model,depth,quantity,tlo,thi,lo,hi,value,stderr,bin_unit,value_unit\n";
    for (const BeamJointRow& r : joint)
      if (r.quantity == q)
        text += fmt::format("{},{:.9g},{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{},per photon\n", r.model,
                            r.depth, r.quantity, r.tlo, r.thi, r.lo, r.hi, r.value, r.stderr_, unit);
    if (!write_text(path, text)) return false;
  }
  return true;
}

int run_beam(const BeamArgs& a) {
  if (!a.out.empty() && a.out != "-") check_output_path(a.out, "--output");
  BeamSettings s;
  s.phase = parse_phase_spec(a.phase);
  s.albedo = a.albedo;
  if (!(a.albedo > 0.0 && a.albedo <= 1.0))
    throw Error(fmt::format("--albedo must lie in (0, 1] (got {})", a.albedo));
  s.depths = parse_number_list("--depths", a.depths);
  if (a.geometry == "infinite") {
    if (a.n_given && a.n != 1.0) throw Error("--n needs --geometry slab:D");
  } else if (a.geometry.rfind("slab:", 0) == 0) {
    s.thickness = parse_number_list("--geometry slab:D", a.geometry.substr(5)).at(0);
    if (!(s.thickness > 0.0)) throw Error("--geometry slab:D needs D > 0");
  } else {
    throw Error(fmt::format("--geometry '{}': use infinite or slab:D", a.geometry));
  }
  if (!(a.n > 0.0)) throw Error("--n must be > 0");
  s.n = a.n;
  if (!(a.photons >= 20.0) || a.photons > 1e12 || a.photons != std::floor(a.photons))
    throw Error("--photons must be a whole number >= 20");
  s.photons = uint64_t(a.photons);
  s.seed = a.seed;
  if (!a.theta_edges.empty()) s.theta_edges = parse_number_list("--theta-edges", a.theta_edges);
  if (!a.r_edges.empty()) s.r_edges = parse_number_list("--r-edges", a.r_edges);
  if (a.time_given) s.time_edges = parse_time_edges("--time-edges", a.time_edges);
  // Each batch of the Monte Carlo keeps every delay bin at every depth (photon_mc.h).
  if (a.time_given && double(s.time_edges.size() + 4) * double(s.depths.size() + 2) > 4e6)
    throw Error(
        fmt::format("--time-edges: {} bins at {} depths need more memory than allowed (bins x depths "
                    "at most about 4e6)",
                    s.time_edges.size() - 1, s.depths.size()));
  check_joint_options(a, s);
  const std::vector<std::string> models = a.models.empty() ? beam_model_names() : split_names(a.models);
  if (models.empty()) throw Error("--models: empty list");
  if ((s.joint_angle || s.joint_radius) && std::find(models.begin(), models.end(), "mc") == models.end())
    throw Error(fmt::format("{}: joint tables come from the model mc; add it to --models",
                            s.joint_angle ? "--delay-angle-csv" : "--delay-radius-csv"));

  std::vector<BeamJointRow> joint;
  const std::vector<BeamRow> rows = beam_table(s, models, &joint);
  // The units of each row's bins and values, in the last two columns (after the columns scripts read).
  auto units = [](const std::string& q) -> std::pair<const char*, const char*> {
    if (q == "angular") return {"rad", "1/sr per photon"};
    if (q == "radial") return {"mfp", "1/mfp^2 per photon"};
    if (q == "delay") return {"mfp", "per photon"};
    if (q == "delay_mean") return {"none", "mfp"};
    if (q == "delay_variance") return {"none", "mfp^2"};
    return {"none", "per photon"};
  };
  std::string text = "model,depth,quantity,lo,hi,value,stderr,bin_unit,value_unit\n";
  for (const BeamRow& r : rows) {
    const auto [bin_unit, value_unit] = units(r.quantity);
    text += fmt::format("{},{:.9g},{},{:.9g},{:.9g},{:.9g},{:.9g},{},{}\n", r.model, r.depth, r.quantity,
                        r.lo, r.hi, r.value, r.stderr_, bin_unit, value_unit);
  }
  if (!write_text(a.out, text)) return kExitFailure;
  return write_joint_tables(a, joint) ? kExitOk : kExitFailure;
}

}  // namespace

void add_beam_command(CLI::App& app, Action& action) {
  auto args = std::make_shared<BeamArgs>();
  auto* cmd =
      app.add_subcommand("beam",
                         "Pencil beam into a scattering medium: photon Monte Carlo against the small-angle "
                         "propagators (lengths in scattering mean free paths)");
  cmd->add_option("--phase", args->phase, "Phase function: iso, hg:G, dhg:G1,G2,W, gauss:THETA2, mie:NAME")
      ->required();
  cmd->add_option("--albedo", args->albedo, "Single-scattering albedo b/c in (0, 1]")->required();
  cmd->add_option("--depths", args->depths, "Optical depths b z of the tally planes, comma-separated")
      ->required();
  cmd->add_option("--geometry", args->geometry, "infinite (default) or slab:D (D in mean free paths)");
  auto* n_opt = cmd->add_option("--n", args->n, "Refractive index of the slab against 1 outside (default 1)");
  cmd->add_option("--photons", args->photons, "Monte Carlo photons (default 1e6)");
  cmd->add_option("--models", args->models, "Comma-separated subset of mc,dolin,tes87,mfs,gsa (default all)");
  cmd->add_option("--theta-edges", args->theta_edges, "Polar-angle bin edges [rad], comma-separated");
  cmd->add_option("--r-edges", args->r_edges, "Radius bin edges [mean free paths], comma-separated");
  cmd->add_option("--seed", args->seed, "Random seed (default 1)");
  cmd->add_option("-o,--output", args->out, "Output CSV (default stdout)");
  auto* te = cmd->add_option("--time-edges", args->time_edges,
                             "Delay-bin edges t0,t1,... or lo:hi:N [mfp]: adds delay rows (mc, mfs, gsa)");
  cmd->add_option("--delay-angle-csv", args->angle_csv,
                  "Joint delay x polar angle table of mc (needs --time-edges; bins of --theta-edges)");
  cmd->add_option("--delay-radius-csv", args->radius_csv,
                  "Joint delay x radius table of mc (needs --time-edges; bins of --r-edges)");
  cmd->callback([args, n_opt, te, &action] {
    args->n_given = n_opt->count() > 0;
    args->time_given = te->count() > 0;
    action = [args] { return run_beam(*args); };
  });
}

}  // namespace nimbus::cli
