// nimbus.beam and nimbus.slab (docs/python.md, "Transport"): what `nimbus beam` and `nimbus slab` compute
// (transport/beam_table.h, transport/photon_mc.h), as dicts of numpy arrays instead of CSV text.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "core/math.h"
#include "media/phase.h"
#include "nimbus/error.h"
#include "py_common.h"
#include "transport/beam_table.h"
#include "transport/phase_spec.h"
#include "transport/photon_mc.h"

namespace nimbus::python {

namespace {

uint64_t photon_count(double photons) {
  if (!(photons >= 20.0) || photons > 1e12 || photons != std::floor(photons))
    throw Error("photons must be a whole number >= 20");
  return uint64_t(photons);
}

py::array_t<double> vec(const std::vector<double>& v) { return double_array(v, {py::ssize_t(v.size())}); }

// One model's rows as arrays: angular and radial (depth x bin) and unscattered (depth), with stderr.
py::dict model_arrays(const std::vector<BeamRow>& rows, const std::string& model,
                      const std::vector<double>& depths, size_t n_theta, size_t n_r) {
  const size_t D = depths.size();
  std::map<std::string, std::vector<double>> value, err;
  const std::map<std::string, size_t> width = {{"angular", n_theta}, {"radial", n_r}, {"unscattered", 1}};
  for (const auto& [q, w] : width) value[q].assign(D * w, 0.0), err[q].assign(D * w, 0.0);
  std::map<std::string, std::vector<size_t>> filled;  // per quantity, rows seen per depth
  for (const auto& [q, w] : width) filled[q].assign(D, 0);
  for (const BeamRow& r : rows) {
    if (r.model != model) continue;
    const size_t d = size_t(
        std::min_element(depths.begin(), depths.end(),
                         [&](double a, double b) { return std::abs(a - r.depth) < std::abs(b - r.depth); }) -
        depths.begin());
    const size_t w = width.at(r.quantity), k = filled[r.quantity][d]++;
    if (k >= w) throw Error("internal: more beam rows than bins");
    value[r.quantity][d * w + k] = r.value;
    err[r.quantity][d * w + k] = r.stderr_;
  }
  py::dict out;
  for (const auto& [q, w] : width) {
    const std::vector<py::ssize_t> shape = q == "unscattered"
                                               ? std::vector<py::ssize_t>{py::ssize_t(D)}
                                               : std::vector<py::ssize_t>{py::ssize_t(D), py::ssize_t(w)};
    out[py::str(q)] = double_array(value[q], shape);
    out[py::str(q + "_stderr")] = double_array(err[q], shape);
  }
  return out;
}

py::dict beam_py(const std::string& phase, double albedo, const std::vector<double>& depths,
                 std::optional<double> thickness, double n, double photons,
                 std::optional<std::vector<std::string>> models,
                 std::optional<std::vector<double>> theta_edges, std::optional<std::vector<double>> r_edges,
                 uint64_t seed) {
  BeamSettings s;
  s.phase = parse_phase_spec(phase);
  s.albedo = albedo;
  s.depths = depths;
  if (thickness) {
    if (!(*thickness > 0.0) || !std::isfinite(*thickness))
      throw Error("thickness must be > 0 (mean free paths)");
    s.thickness = *thickness;
  } else if (n != 1.0) {
    throw Error("n needs a slab (thickness)");
  }
  if (!(n > 0.0) || !std::isfinite(n)) throw Error("n must be > 0");
  s.n = n;
  s.photons = photon_count(photons);
  s.seed = seed;
  s.theta_edges = theta_edges.value_or(default_theta_edges());
  s.r_edges = r_edges.value_or(default_r_edges());
  const std::vector<std::string> names = models.value_or(beam_model_names());
  if (names.empty()) throw Error("models: empty list");
  std::vector<BeamRow> rows;
  {
    py::gil_scoped_release release;
    rows = beam_table(s, names);
  }
  py::dict out;
  out["depths"] = vec(s.depths);
  out["theta_edges"] = vec(s.theta_edges);
  out["r_edges"] = vec(s.r_edges);
  out["models"] = names;
  for (const std::string& m : names)
    out[py::str(m)] = model_arrays(rows, m, s.depths, s.theta_edges.size() - 1, s.r_edges.size() - 1);
  return out;
}

py::dict slab_py(double mu_s, double mu_a, double thickness, double g, std::optional<std::string> phase,
                 double n, double photons, uint64_t seed, int angle_bins, int r_bins,
                 std::optional<double> r_max) {
  if (!(g > -1.0 && g < 1.0)) throw Error(fmt::format("g must lie in (-1, 1) (got {})", g));
  if (phase && g != 0.0) throw Error("give g (Henyey-Greenstein) or phase, not both");
  if (!(n >= 1.0 && n <= 10.0)) throw Error(fmt::format("n must lie in [1, 10] (got {})", n));
  if (!(thickness > 0.0) || !std::isfinite(thickness))
    throw Error(fmt::format("thickness must be > 0 (got {})", thickness));
  if (!std::isfinite(mu_s + mu_a)) throw Error("mu_s + mu_a must be finite");
  if (angle_bins < 1 || r_bins < 1) throw Error("angle_bins and r_bins must be >= 1");
  PhotonMcSettings s;
  s.sigma_s = mu_s;
  s.sigma_a = mu_a;
  s.phase = phase ? parse_phase_spec(*phase) : Phase{HgPhase{g}};
  s.thickness = thickness;
  s.n = n;
  s.photons = photon_count(photons);
  s.seed = seed;
  s.batches = 20;  // as `nimbus slab`
  for (int i = 0; i <= angle_bins; ++i) s.theta_edges.push_back(0.5 * kPi * i / angle_bins);
  // The default largest radius of `nimbus slab`: 5 transport lengths or 5 thicknesses.
  const double transport = mu_a + mu_s * (1.0 - phase_mean_cosine(s.phase));
  const double rm = r_max ? *r_max : 5.0 * std::max(thickness, transport > 0.0 ? 1.0 / transport : thickness);
  if (!(rm > 0.0) || !std::isfinite(rm)) throw Error("r_max must be > 0");
  for (int i = 0; i <= r_bins; ++i) s.r_edges.push_back(rm * i / r_bins);
  PhotonMcResult r;
  {
    py::gil_scoped_release release;
    r = run_photon_mc(s);
  }
  py::dict out;
  auto scalar = [&](const char* name, const Estimate& e) {
    out[name] = e.value;
    out[py::str(std::string(name) + "_stderr")] = e.err;
  };
  scalar("specular", r.specular);
  scalar("diffuse_reflectance", r.diffuse_reflectance);
  scalar("transmittance", r.transmittance);
  scalar("unscattered_transmittance", r.unscattered_transmittance);
  scalar("absorbed", r.absorbed);
  out["theta_edges"] = vec(s.theta_edges);
  out["r_edges"] = vec(s.r_edges);
  auto binned = [&](const char* name, const std::vector<Estimate>& v) {
    std::vector<double> value, err;
    for (const Estimate& e : v) value.push_back(e.value), err.push_back(e.err);
    out[name] = vec(value);
    out[py::str(std::string(name) + "_stderr")] = vec(err);
  };
  binned("reflect_angular", r.reflect_angular);
  binned("reflect_radial", r.reflect_radial);
  binned("transmit_angular", r.transmit_angular);
  binned("transmit_radial", r.transmit_radial);
  return out;
}

}  // namespace

void init_transport(py::module_& m) {
  m.def("beam", &beam_py, py::arg("phase"), py::arg("albedo"), py::arg("depths"),
        py::arg("thickness") = py::none(), py::arg("n") = 1.0, py::arg("photons") = 1e6,
        py::arg("models") = py::none(), py::arg("theta_edges") = py::none(), py::arg("r_edges") = py::none(),
        py::arg("seed") = 1,
        R"(A pencil beam into a forward-scattering medium: photon Monte Carlo ('mc') against the small-angle
propagators ('dolin', 'tes87', 'mfs', 'gsa'), tallied at planes of given optical depth; what
`nimbus beam` writes as CSV. Lengths in scattering mean free paths (b = 1).

phase: 'iso', 'hg:G', 'dhg:G1,G2,W', 'gauss:THETA2' or 'mie:NAME' (as `nimbus beam --phase`).
albedo: single-scattering albedo b/c in (0, 1].  depths: optical depths b z of the planes, increasing.
thickness: None for an infinite medium, else a slab [0, D] (mfp) of refractive index n.
photons: Monte Carlo photons.  models: a subset of nimbus.beam_models() (default all).
theta_edges [rad], r_edges [mfp]: bin edges (defaults: fine near 0, as the CLI's).

Returns {'depths' (D,), 'theta_edges' (A+1,) [rad], 'r_edges' (R+1,) [mfp], 'models': [...], and per
model {'angular': (D, A) plane-integrated scattered radiance per sr per source photon,
'radial': (D, R) forward scattered flux per unit area [1/mfp^2] per source photon,
'unscattered': (D,) unscattered flux through the plane per source photon, and each with '_stderr'
(the Monte Carlo's standard errors; 0 for the deterministic models)}}.)");
  m.def("beam_models", &beam_model_names, "The models nimbus.beam compares.");
  m.def("slab", &slab_py, py::arg("mu_s"), py::arg("mu_a"), py::arg("thickness"), py::arg("g") = 0.0,
        py::arg("phase") = py::none(), py::arg("n") = 1.0, py::arg("photons") = 1e6, py::arg("seed") = 1,
        py::arg("angle_bins") = 30, py::arg("r_bins") = 50, py::arg("r_max") = py::none(),
        R"(Photon Monte Carlo of a pencil beam normally incident on a slab, MCML conventions (Wang, Jacques &
Zheng 1995); what `nimbus slab --csv` computes. Any consistent length unit.

mu_s, mu_a: scattering and absorption coefficients [1/length].  thickness: the slab's [length].
g: Henyey-Greenstein asymmetry, or phase: any phase spec of nimbus.beam ('dhg:0.9,-0.3,0.9', ...).
n: the slab's refractive index against 1 outside, in [1, 10].
angle_bins: exit-angle bins over [0, pi/2]; r_bins: exit-radius bins over [0, r_max] (default
r_max: 5 transport lengths or 5 thicknesses, whichever is larger).

Returns {'specular', 'diffuse_reflectance', 'transmittance' (unscattered included),
'unscattered_transmittance', 'absorbed': fractions of the incident power, each with '_stderr';
'theta_edges' (angle_bins+1,) [rad, exit polar angle outside the slab], 'r_edges' (r_bins+1,)
[length]; 'reflect_angular', 'transmit_angular' (angle_bins,) per sr of exit solid angle;
'reflect_radial', 'transmit_radial' (r_bins,) per unit area [1/length^2]; each with '_stderr'}.)");
}

}  // namespace nimbus::python
