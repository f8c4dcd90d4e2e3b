// The beam table behind `nimbus beam`: photon Monte Carlo and every deterministic propagator (Dolin,
// Tessendorf 87, MFS, generalised small-angle) tallied in the same angular and radial bins at planes
// of given optical depth.
#include "transport/beam_table.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/math.h"
#include "nimbus/error.h"
#include "transport/gsa_delay.h"
#include "transport/mfs_kernel.h"
#include "transport/photon_mc.h"
#include "transport/small_angle.h"
#include "transport/time_resolved.h"

namespace nimbus {

std::vector<double> default_theta_edges() {
  std::vector<double> e{0.0};
  double w = 0.002;
  while (e.back() + w < kPi - 0.05) {
    e.push_back(e.back() + w);
    w = std::min(w * 1.12, 0.1);
  }
  e.push_back(kPi);
  return e;
}

std::vector<double> default_r_edges() {
  std::vector<double> e{0.0};
  double w = 0.002;
  while (e.back() < 100.0) {
    e.push_back(e.back() + w);
    w *= 1.15;
  }
  return e;
}

const std::vector<std::string>& beam_model_names() {
  static const std::vector<std::string> names{"mc", "dolin", "tes87", "mfs", "gsa"};
  return names;
}

namespace {

// The settings with defaults filled in, after checking them and the model names.
BeamSettings checked_beam_settings(const BeamSettings& in, const std::vector<std::string>& models) {
  BeamSettings s = in;
  if (!(s.albedo > 0.0 && s.albedo <= 1.0))
    throw Error(fmt::format("albedo must lie in (0, 1] (got {})", s.albedo));
  if (s.depths.empty()) throw Error("at least one depth is needed");
  for (size_t i = 0; i < s.depths.size(); ++i) {
    if (!(s.depths[i] > 0.0) || !std::isfinite(s.depths[i]))
      throw Error(fmt::format("depth {} must be > 0", s.depths[i]));
    if (i > 0 && !(s.depths[i] > s.depths[i - 1])) throw Error("depths must increase");
    if (!(s.depths[i] < s.thickness))
      throw Error(fmt::format("depth {} must lie inside the slab (thickness {})", s.depths[i], s.thickness));
  }
  if (s.theta_edges.empty()) s.theta_edges = default_theta_edges();
  if (s.r_edges.empty()) s.r_edges = default_r_edges();
  if (s.time_edges.size() == 1) throw Error("delay edges need at least two values");
  for (const std::vector<double>* e : {&s.theta_edges, &s.r_edges})
    if (e->size() < 2) throw Error("bin edges need at least two values");
  for (const auto& m : models)
    if (m != "mc_fwd" &&
        std::find(beam_model_names().begin(), beam_model_names().end(), m) == beam_model_names().end())
      throw Error(
          fmt::format("unknown model '{}' (known: mc, dolin, tes87, mfs, gsa; diagnostic: mc_fwd)", m));
  return s;
}

// Rows of a deterministic model at depth z from its cumulative angular and radial power; `entry` is
// the fraction that enters the medium, `a` the absorption per scattering length.
template <typename WithinAngle, typename WithinRadius>
void add_model_rows(std::vector<BeamRow>& rows, const BeamSettings& s, const std::string& name, double z,
                    double entry, double a, WithinAngle&& within_angle, WithinRadius&& within_radius) {
  const auto& te = s.theta_edges;
  const auto& re = s.r_edges;
  auto solid_angle = [&](size_t i) { return 2.0 * kPi * (std::cos(te[i]) - std::cos(te[i + 1])); };
  auto area = [&](size_t i) { return kPi * (re[i + 1] * re[i + 1] - re[i] * re[i]); };
  double prev = within_angle(te[0]);
  for (size_t i = 0; i + 1 < te.size(); ++i) {
    const double next = within_angle(te[i + 1]);
    rows.push_back({name, z, "angular", te[i], te[i + 1], entry * (next - prev) / solid_angle(i), 0.0});
    prev = next;
  }
  prev = within_radius(re[0]);
  for (size_t i = 0; i + 1 < re.size(); ++i) {
    const double next = within_radius(re[i + 1]);
    rows.push_back({name, z, "radial", re[i], re[i + 1], entry * (next - prev) / area(i), 0.0});
    prev = next;
  }
  rows.push_back({name, z, "unscattered", 0.0, 0.0, entry * std::exp(-(1.0 + a) * z), 0.0});
}

// Rows `delay` of one model at depth z: the bins, a first row from 0 if the first edge is > 0, a last
// row to infinity.
template <typename Bin>
void add_delay_rows(std::vector<BeamRow>& rows, const BeamSettings& s, const std::string& model, double z,
                    Bin&& bin, const Estimate& before, const Estimate& after) {
  const auto& e = s.time_edges;
  if (e.front() > 0.0) rows.push_back({model, z, "delay", 0.0, e.front(), before.value, before.err});
  for (size_t i = 0; i + 1 < e.size(); ++i) {
    const Estimate v = bin(i);
    rows.push_back({model, z, "delay", e[i], e[i + 1], v.value, v.err});
  }
  rows.push_back(
      {model, z, "delay", e.back(), std::numeric_limits<double>::infinity(), after.value, after.err});
}

// The joint rows of one model at one plane: for each angle (or radius) bin of `edges` and the outside
// slot (lo = hi = -1), the delay bins as add_delay_rows lays them out; value(j, t0, t1) the estimate of
// bin j (edges.size() - 1: outside) and delay [t0, t1).
template <typename Value>
void add_joint_rows(std::vector<BeamJointRow>& rows, const BeamSettings& s, const std::string& model,
                    double z, const std::string& q, const std::vector<double>& edges, Value&& value) {
  const auto& e = s.time_edges;
  const double inf = std::numeric_limits<double>::infinity();
  for (size_t j = 0; j < edges.size(); ++j) {
    const bool out = j + 1 == edges.size();
    const double lo = out ? -1.0 : edges[j], hi = out ? -1.0 : edges[j + 1];
    auto add = [&](double t0, double t1) {
      const Estimate v = value(j, t0, t1);
      rows.push_back({model, z, q, t0, t1, lo, hi, v.value, v.err});
    };
    if (e.front() > 0.0) add(0.0, e.front());
    for (size_t i = 0; i + 1 < e.size(); ++i) add(e[i], e[i + 1]);
    add(e.back(), inf);
  }
}

// The MC's joint rows at plane t: the slots of its TimeTally per bin, found by the delay bin's start.
void add_mc_joint_rows(std::vector<BeamJointRow>& rows, const BeamSettings& s, const PlaneTally& t,
                       const std::string& q, const std::vector<double>& edges,
                       const std::vector<TimeTally>& tallies) {
  const auto& e = s.time_edges;
  add_joint_rows(rows, s, "mc", t.depth, q, edges, [&](size_t j, double t0, double) {
    if (t0 < e.front()) return tallies[j].before;
    if (t0 >= e.back()) return tallies[j].after;
    return tallies[j].bins[size_t(std::lower_bound(e.begin(), e.end(), t0) - e.begin())];
  });
}

// The photon Monte Carlo rows: "mc" if asked, the forward-only "mc_fwd" diagnostic if want_fwd.
void add_mc_rows(std::vector<BeamRow>& rows, std::vector<BeamJointRow>* joint, const BeamSettings& s,
                 double a, bool asked, bool want_fwd) {
  const auto& te = s.theta_edges;
  const auto& re = s.r_edges;
  PhotonMcSettings mc;
  mc.sigma_s = 1.0;
  mc.sigma_a = a;
  mc.phase = s.phase;
  mc.thickness = s.thickness;
  mc.n = s.n;
  mc.plane_depths = s.depths;
  mc.theta_edges = te;
  mc.r_edges = re;
  mc.photons = s.photons;
  mc.seed = s.seed;
  mc.batches = s.batches;
  mc.time_edges = s.time_edges;
  mc.joint_angle = asked && s.joint_angle;
  mc.joint_radius = asked && s.joint_radius;
  const PhotonMcResult r = run_photon_mc(mc);
  for (const PlaneTally& t : r.planes) {
    if (want_fwd)
      for (size_t i = 0; i < t.angular.size(); ++i)
        rows.push_back({"mc_fwd", t.depth, "angular", te[i], te[i + 1], t.angular_forward_only[i].value,
                        t.angular_forward_only[i].err});
    if (want_fwd && !s.time_edges.empty()) {
      add_delay_rows(
          rows, s, "mc_fwd", t.depth, [&](size_t i) { return t.delay_forward_only.bins[i]; },
          t.delay_forward_only.before, t.delay_forward_only.after);
      rows.push_back({"mc_fwd", t.depth, "delay_mean", 0.0, 0.0, t.delay_mean_forward_only.value,
                      t.delay_mean_forward_only.err});
      rows.push_back({"mc_fwd", t.depth, "delay_variance", 0.0, 0.0, t.delay_variance_forward_only.value,
                      t.delay_variance_forward_only.err});
    }
    if (!asked) continue;
    for (size_t i = 0; i < t.angular.size(); ++i)
      rows.push_back({"mc", t.depth, "angular", te[i], te[i + 1], t.angular[i].value, t.angular[i].err});
    for (size_t i = 0; i < t.radial.size(); ++i)
      rows.push_back({"mc", t.depth, "radial", re[i], re[i + 1], t.radial[i].value, t.radial[i].err});
    rows.push_back({"mc", t.depth, "unscattered", 0.0, 0.0, t.unscattered.value, t.unscattered.err});
    if (s.time_edges.empty()) continue;
    add_delay_rows(
        rows, s, "mc", t.depth, [&](size_t i) { return t.delay.bins[i]; }, t.delay.before, t.delay.after);
    rows.push_back({"mc", t.depth, "delay_mean", 0.0, 0.0, t.delay_mean.value, t.delay_mean.err});
    rows.push_back({"mc", t.depth, "delay_variance", 0.0, 0.0, t.delay_variance.value, t.delay_variance.err});
    if (mc.joint_angle) add_mc_joint_rows(*joint, s, t, "delay_angle", te, t.delay_angle);
    if (mc.joint_radius) add_mc_joint_rows(*joint, s, t, "delay_radius", re, t.delay_radius);
  }
}

// The corrected MFS kernel's delay rows at depth z (time_resolved.h), times n (time = n * path).
void add_mfs_delay_rows(std::vector<BeamRow>& rows, const BeamSettings& s, double z, double entry, double a) {
  const double theta2 = phase_theta2(s.phase), n = s.n, inf = std::numeric_limits<double>::infinity();
  const auto& e = s.time_edges;
  auto within = [&](double lo, double hi) {
    return Estimate{entry * mfs_delay_within(lo / n, hi / n, z, 1.0, a, theta2), 0.0};
  };
  add_delay_rows(
      rows, s, "mfs", z, [&](size_t i) { return within(e[i], e[i + 1]); }, within(0.0, e.front()),
      within(e.back(), inf));
  const DelayMoments m = mfs_delay_moments(z, 1.0, a, theta2);
  rows.push_back({"mfs", z, "delay_mean", 0.0, 0.0, n * m.mean, 0.0});
  rows.push_back({"mfs", z, "delay_variance", 0.0, 0.0, n * n * m.variance, 0.0});
}

// The generalised propagator's delay rows at depth z: the exact small-angle moments of its deflection
// law and the moment-matched gamma law in the bins (gsa_delay.h), times n.
void add_gsa_delay_rows(std::vector<BeamRow>& rows, const BeamSettings& s, double z, double entry, double a,
                        const DeflectionMoments& dm) {
  const GammaDelayLaw g = gsa_delay_law(z, 1.0, a, dm);
  const double n = s.n, inf = std::numeric_limits<double>::infinity();
  const auto& e = s.time_edges;
  auto within = [&](double lo, double hi) { return Estimate{entry * g.within(lo / n, hi / n), 0.0}; };
  add_delay_rows(
      rows, s, "gsa", z, [&](size_t i) { return within(e[i], e[i + 1]); }, within(0.0, e.front()),
      within(e.back(), inf));
  rows.push_back({"gsa", z, "delay_mean", 0.0, 0.0, n * g.mean(), 0.0});
  rows.push_back({"gsa", z, "delay_variance", 0.0, 0.0, n * n * g.variance(), 0.0});
}

}  // namespace

std::vector<BeamRow> beam_table(const BeamSettings& in, const std::vector<std::string>& models,
                                std::vector<BeamJointRow>* joint) {
  const BeamSettings s = checked_beam_settings(in, models);
  if ((s.joint_angle || s.joint_radius) && (s.time_edges.empty() || !joint))
    throw Error("joint delay tables need delay edges and somewhere to put their rows");
  const bool want_fwd = std::find(models.begin(), models.end(), "mc_fwd") != models.end();
  const double a = (1.0 - s.albedo) / s.albedo;  // absorption per scattering length
  const bool slab = std::isfinite(s.thickness);
  const double entry = slab ? 1.0 - fresnel_reflectance(1.0, s.n, 1.0) : 1.0;

  std::vector<BeamRow> rows;
  for (const std::string& m : beam_model_names()) {
    const bool asked = std::find(models.begin(), models.end(), m) != models.end();
    if (!asked && !(m == "mc" && want_fwd)) continue;
    if (m == "mc") {
      add_mc_rows(rows, joint, s, a, asked, want_fwd);
    } else if (m == "gsa") {
      const ForwardPropagator prop(s.phase);
      const DeflectionMoments dm = s.time_edges.empty() ? DeflectionMoments{} : deflection_moments(s.phase);
      for (double z : s.depths) {
        const ForwardProfile p = prop.profile(z, a * z);
        add_model_rows(
            rows, s, m, z, entry, a, [&](double t) { return p.angular_within(t); },
            [&](double r) { return p.radial_within(r); });
        if (!s.time_edges.empty()) add_gsa_delay_rows(rows, s, z, entry, a, dm);
      }
    } else {
      const GaussianModel gm = m == "dolin"   ? GaussianModel::Dolin
                               : m == "tes87" ? GaussianModel::Tes87
                                              : GaussianModel::Mfs;
      const double theta2 = phase_theta2(s.phase);
      for (double z : s.depths) {
        const GaussianBeam g = gaussian_beam(gm, z, z, a * z, theta2);
        add_model_rows(
            rows, s, m, z, entry, a, [&](double t) { return g.angular_within(t); },
            [&](double r) { return g.radial_within(r); });
        if (gm == GaussianModel::Mfs && !s.time_edges.empty()) add_mfs_delay_rows(rows, s, z, entry, a);
      }
    }
  }
  return rows;
}

}  // namespace nimbus
