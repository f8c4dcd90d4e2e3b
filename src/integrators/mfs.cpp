#include "integrators/mfs.h"

#include <fmt/format.h>

#include "integrators/tracking.h"
#include "core/json_reader.h"
#include "nimbus/error.h"

namespace nimbus {

namespace {
const std::vector<std::string> kLightPathNames = {"forward", "beer_lambert"};
const std::vector<std::string> kPropagatorNames = {"gsa", "gaussian"};
const std::vector<std::string> kPhotonTransportNames = {"exact", "similarity"};
const std::vector<std::string> kForwardSideNames = {"camera", "light"};
}  // namespace

MfsSettings mfs_settings_from_json(const nlohmann::json& options, const std::string& where) {
  MfsSettings s;
  JsonObject o(options, where, "/integrator");
  s.tau_step = o.number("tau_step", 1e-4, 100.0, s.tau_step);
  s.step_growth = o.number("step_growth", 0.0, 100.0, s.step_growth);
  s.light_path = LightPath(o.choice("light_path", kLightPathNames, int(s.light_path)));
  s.propagator = Propagator(o.choice("propagator", kPropagatorNames, int(s.propagator)));
  if (double f = 0.0; o.keyword_or_number("peak_fraction", "auto", 0.0, 0.99, &f)) s.peak_fraction = f;
  if (int64_t k = 0; o.keyword_or_integer("large_angle_scatters", "all", 0, 1024, &k)) s.large_angle_scatters = int(k);
  s.photons = int(o.integer("photons", 1, 1 << 26, s.photons));
  s.photon_transport =
      PhotonTransport(o.choice("photon_transport", kPhotonTransportNames, int(s.photon_transport)));
  if (int64_t n = 0; o.keyword_or_integer("scatter_grid_resolution", "auto", 4, 96, &n))
    s.scatter_grid_resolution = int(n);
  s.scatter_grid_bands = int(o.integer("scatter_grid_bands", 1, kShMaxBands, s.scatter_grid_bands));
  s.forward_side = ForwardSide(o.choice("forward_side", kForwardSideNames, int(s.forward_side)));
  s.beam_photons = int(o.integer("beam_photons", 0, 1 << 24, s.beam_photons));
  s.light_blur = o.boolean("light_blur", s.light_blur);
  s.path_lengthening = o.boolean("path_lengthening", s.path_lengthening);
  s.filtered_lookups = o.boolean("filtered_lookups", s.filtered_lookups);
  s.shadow_map_resolution = int(o.integer("shadow_map_resolution", 8, 1024, s.shadow_map_resolution));
  o.finish();
  // The light side carries the light to every scatter through peak scatters, with photons in the true
  // medium: other choices would be silently overridden, so they are errors.
  if (s.light_side() && !s.forward_light_path())
    o.fail("light_path", "\"beer_lambert\" conflicts with " + o.path_of("forward_side") +
                             " \"light\" (the light side needs \"forward\")");
  if (s.light_side() && s.photon_transport != PhotonTransport::exact)
    o.fail("photon_transport", "\"similarity\" conflicts with " + o.path_of("forward_side") +
                                   " \"light\" (the light side needs \"exact\")");
  return s;
}

nlohmann::json to_json(const MfsSettings& s) {
  nlohmann::json j = {{"tau_step", s.tau_step},
                      {"step_growth", s.step_growth},
                      {"light_path", kLightPathNames[int(s.light_path)]},
                      {"propagator", kPropagatorNames[int(s.propagator)]},
                      {"photons", s.photons},
                      {"photon_transport", kPhotonTransportNames[int(s.photon_transport)]},
                      {"scatter_grid_bands", s.scatter_grid_bands},
                      {"forward_side", kForwardSideNames[int(s.forward_side)]},
                      {"beam_photons", s.beam_photons},
                      {"light_blur", s.light_blur},
                      {"path_lengthening", s.path_lengthening},
                      {"filtered_lookups", s.filtered_lookups},
                      {"shadow_map_resolution", s.shadow_map_resolution}};
  j["peak_fraction"] = s.peak_fraction ? nlohmann::json(*s.peak_fraction) : nlohmann::json("auto");
  j["large_angle_scatters"] =
      s.large_angle_scatters ? nlohmann::json(*s.large_angle_scatters) : nlohmann::json("all");
  j["scatter_grid_resolution"] =
      s.scatter_grid_resolution ? nlohmann::json(*s.scatter_grid_resolution) : nlohmann::json("auto");
  return j;
}

MfsIntegrator::MfsIntegrator(const SceneContext& context, MfsSettings settings, uint64_t seed)
    : ctx_(context), s_(settings) {
  for (int i = 0; i < ctx_.media.count(); ++i) {
    const Phase& phase = ctx_.media.phase(i);
    const double f = s_.peak_fraction ? *s_.peak_fraction : std::min(0.99, auto_peak_fraction(phase));
    splits_.push_back(std::make_unique<PhaseSplit>(phase, f, s_.propagator == Propagator::gaussian));
    f_.push_back(splits_.back()->f());
    theta2_.push_back(splits_.back()->theta2());
  }
  // Shadow-map nodes march towards the light at this optical-depth step (midpoint rule). 0.05 and 0.5
  // give the same validation errors (the map's trilinear interpolation dominates); 0.25 halves the
  // Disney cloud's precomputation against 0.05.
  constexpr double map_step = 0.25;
  for (const Light& l : ctx_.lights) {
    full_maps_.emplace_back(ctx_.media, ctx_.majorants, l, s_.shadow_map_resolution, map_step);
    if (s_.forward_light_path())
      reduced_maps_.emplace_back(ctx_.media, ctx_.majorants, l, s_.shadow_map_resolution, map_step, f_);
  }
  if (!s_.scatter_grid_resolution) {
    // "auto": cells of at most ~1.6 optical depths at the medium's typical extinction (the mean of the
    // majorant grid's non-empty cells), 32 to 64 nodes along the longest axis: 32 up to an optical size
    // of ~50 across. (A uniform medium's whole extinction; a cloud's dense core counts less.)
    const Bounds b = ctx_.media.bounds();
    double sum = 0.0;
    size_t cells = 0;
    const auto res = ctx_.majorants.resolution();
    for (int z = 0; z < res[2]; ++z)
      for (int y = 0; y < res[1]; ++y)
        for (int x = 0; x < res[0]; ++x)
          if (const double m = ctx_.majorants.cell_majorant(x, y, z); m > 0.0) sum += m, ++cells;
    const Vec3 e = b.empty() ? Vec3(0.0) : b.hi - b.lo;
    const double across = cells > 0 ? std::max({e.x, e.y, e.z}) * sum / double(cells) : 0.0;
    s_.scatter_grid_resolution =
        std::isfinite(across) ? int(std::clamp(std::ceil(across / 1.6), 32.0, 64.0)) : 64;
  }
  std::vector<const PhaseSplit*> splits;  // for the photon grids
  for (const auto& sp : splits_) splits.push_back(sp.get());
  if (s_.forward_light_path() && s_.beam_photons > 0 && !ctx_.lights.empty()) {
    beam_ = std::make_unique<BeamGrid>(ctx_, splits, f_, reduced_maps_, s_.beam_photons,
                                       *s_.scatter_grid_resolution, seed);
  }
  // Wide scatters 2 .. K from the scatter grid (for K = 1 only the environment's light).
  if (s_.large_angle_scatters != 0 && (s_.large_angle_scatters != 1 || ctx_.has_environment)) {
    ScatterGridSettings grid;
    grid.photons = s_.photons;
    grid.resolution = *s_.scatter_grid_resolution;
    grid.max_wide_scatters = s_.large_angle_scatters.value_or(0);
    grid.exact_transport = s_.photon_transport == PhotonTransport::exact;
    grid.bands = s_.scatter_grid_bands;
    grid.seed = seed;
    grid_ = std::make_unique<ScatterGrid>(ctx_, splits, f_, grid);
  }
}

size_t MfsIntegrator::memory_bytes() const {
  size_t bytes = (grid_ ? grid_->memory_bytes() : 0) + (beam_ ? beam_->memory_bytes() : 0);
  for (const auto& m : full_maps_) bytes += m.memory_bytes();
  for (const auto& m : reduced_maps_) bytes += m.memory_bytes();
  return bytes;
}

namespace {
// 1 / cosh(sqrt(theta tau)): the extra loss on paths lengthened by peak deflections (the corrected MFS
// kernel's total, W / cosh(z / L) with (z / L)^2 = a theta2 b z^2; notes/mfs-math.md), for an
// accumulated angular diffusion theta = int theta2 dtau_peak and loss depth tau (wide scatters and
// absorption).
double lengthening(double theta, double tau) {
  const double x = std::sqrt(std::max(0.0, theta * tau));
  const double e = std::exp(-x);
  return 2.0 * e / (1.0 + e * e);
}
}  // namespace

Rgb MfsIntegrator::radiance(const Vec3& o, const Vec3& d, Rng& rng) const {
  // T_full: plain transmittance (background); T_red: reduced extinction (wide scatters and absorption);
  // tau_p: peak optical depth, all from the camera to the current point.
  // theta_p: the accumulated angular diffusion int theta2 dtau_p (per-component mean square angle of the
  // peaks), tau_red = -ln T_red: together the path-lengthening factor 1 / cosh(sqrt(theta_p tau_red)).
  Rgb L(0.0), T_full(1.0), T_red(1.0), tau_p(0.0), theta_p(0.0), tau_red(0.0);
  // Moments int theta2 sigma_peak s^k ds (k = 0, 1, 2; s from the ray's origin, largest channel): the
  // lateral variance of the light that reaches the camera from depth t is t^2 m0 - 2 t m1 + m2.
  double m0 = 0.0, m1 = 0.0, m2 = 0.0;
  const double jitter = rng.uniform();
  MediumPoint mp;
  // Steps grow with the camera-side reduced depth: tau_step (1 + step_growth tau_red).
  march_growing(ctx_.majorants, o, d, std::numeric_limits<double>::infinity(), s_.tau_step, jitter,
        [&] { return 1.0 + s_.step_growth * max_component(tau_red); },
        [&](const Vec3& p, double t, double dt) {
          ctx_.media.eval(p, &mp);
          Rgb sigma_peak(0.0), sigma_theta(0.0);
          for (int i = 0; i < mp.count; ++i) {
            sigma_peak += mp.sigma_s_i[i] * f_[i];
            sigma_theta += mp.sigma_s_i[i] * (f_[i] * theta2_[i]);
          }
          const Rgb sigma_red = mp.sigma_t() - sigma_peak;
          if (max_component(mp.sigma_s) > 0.0) {
            // Camera-side depths at the sample point.
            Rgb T_here = s_.light_side() ? T_full * exp(-mp.sigma_t() * (jitter * dt))
                                       : T_red * exp(-sigma_red * (jitter * dt));
            if (!s_.light_side() && s_.path_lengthening)
              for (int c = 0; c < 3; ++c)
                T_here[c] *= lengthening(theta_p[c] + sigma_theta[c] * jitter * dt,
                                         tau_red[c] + sigma_red[c] * jitter * dt);
            const Rgb tp = tau_p + sigma_peak * (jitter * dt);
            Rgb in_scatter(0.0), peak_scatter(0.0);  // towards the camera through T_here / T_full
            for (int i = 0; i < mp.count; ++i) {
              if (max_component(mp.sigma_s_i[i]) <= 0.0) continue;
              const PhaseSplit& split = *splits_[i];
              const double f = f_[i];
              Rgb Li(0.0), Li_peak(0.0);
              // Directional and point lights: wide term and peak term.
              for (size_t l = 0; l < ctx_.lights.size(); ++l) {
                LightSample ls;
                const double u1 = rng.uniform(), u2 = rng.uniform();
                if (!sample_light(ctx_.lights[l], p, u1, u2, &ls)) continue;
                const double mu = dot(d, ls.wi);
                const Rgb T_light = full_maps_[l].lookup(p);
                Rgb T_wide = s_.forward_light_path() ? reduced_maps_[l].lookup(p) : T_light;
                // Light-side peak depth ln(T_wide / T_light) and its path lengthening: from the
                // photon-traced beam where there is one (its loss factor, and the peak depth whose
                // spread has the beam's mean cosine), else the straight-line picture and, optionally,
                // the corrected kernel's 1 / cosh.
                Rgb tps(0.0), R(1.0), mean_cos(1.0);
                const bool traced = beam_ && beam_->lookup(l, p, &R, &mean_cos);
                const double one_minus_chi1 = 1.0 - (split.peak_moments().size() > 1 ? split.peak_moments()[1] : 1.0);
                for (int c = 0; c < 3; ++c) {
                  if (traced) {
                    T_wide[c] *= R[c];
                    tps[c] = one_minus_chi1 > 0.0
                                 ? std::min(PhaseSplit::kTauMax, -std::log(std::max(mean_cos[c], 1e-12)) / one_minus_chi1)
                                 : 0.0;
                    continue;
                  }
                  tps[c] = T_light[c] > 1e-30 ? std::max(0.0, std::log(T_wide[c] / T_light[c]))
                                              : PhaseSplit::kTauMax;
                  if (s_.forward_light_path() && s_.path_lengthening && T_wide[c] > 0.0)
                    T_wide[c] *= lengthening(theta2_[i] * tps[c], -std::log(T_wide[c]));
                }
                if (s_.light_side()) {
                  // The light's peak-only (zero wide scatter) beam at p: total T_wide, spread by the
                  // light-side peak depth ln(T_wide / T_light); scattered by the whole phase function.
                  for (int c = 0; c < 3; ++c) {
                    Li[c] += ls.weight[c] * T_wide[c] *
                             ((1.0 - f) * split.wide_eff(tps[c], mu) + f * split.peak_eff(tps[c], mu));
                  }
                  continue;
                }
                for (int c = 0; c < 3; ++c) {
                  // The first wide scatter: the beam arrives spread by its light-side peak depth, the
                  // scattered light is spread again by the camera-side one; on the sphere these
                  // convolutions multiply the Legendre moments, so the depths add.
                  if (s_.large_angle_scatters != 0)
                    Li[c] += ls.weight[c] * (1.0 - f) * split.wide_eff(tp[c] + (s_.light_blur ? tps[c] : 0.0), mu) *
                             T_wide[c];
                  if (s_.forward_light_path()) {
                    // Paths without a wide scatter, counted at their last peak scatter (here): the light's
                    // forward-scattered beam (total T_wide, spread by the light-side peak depth
                    // ln(T_wide / T_light)), then straight to the camera (plain transmittance).
                    Li_peak[c] += ls.weight[c] * f * split.peak_eff(tps[c], mu) * T_wide[c];
                  } else {
                    // beer_lambert: first (peak) scatter here, unscattered light, the propagator to the
                    // camera.
                    Li[c] += ls.weight[c] * f * split.peak_eff(tp[c], mu) * T_light[c];
                  }
                }
              }
              // Light that already took wide scatters (and the environment's light): its last wide scatter
              // is here.
              if (grid_) {
                const std::vector<double>& chi_w = split.wide_moments();
                const std::vector<double>& chi_p = split.peak_moments();
                auto moment = [](const std::vector<double>& m, int l, double fallback) {
                  return int(m.size()) > l ? m[l] : fallback;
                };
                std::array<Rgb, kShMaxBands> chi;
                for (int l = 0; l < grid_->bands(); ++l) {
                  for (int c = 0; c < 3; ++c) {
                    chi[l][c] =
                        s_.light_side()
                            // Every scatter at p (whole phase function); the camera leg is exact.
                            ? f * moment(chi_p, l, 1.0) + (1.0 - f) * moment(chi_w, l, 0.0)
                            // The wide part's moments after the camera-side peak blur.
                            : moment(chi_w, l, 0.0) * std::exp(-tp[c] * (1.0 - moment(chi_p, l, 1.0)));
                  }
                }
                const double spread = std::sqrt(std::max(0.0, t * t * m0 - 2.0 * t * m1 + m2));
                Li += (s_.light_side() ? 1.0 : 1.0 - f) *
                      (s_.filtered_lookups && !s_.light_side() ? grid_->scattered_filtered(p, -d, chi, spread)
                                                             : grid_->scattered(p, -d, chi));
              }
              in_scatter += mp.sigma_s_i[i] * Li;
              peak_scatter += mp.sigma_s_i[i] * Li_peak;
            }
            L += (T_here * in_scatter + T_full * exp(-mp.sigma_t() * (jitter * dt)) * peak_scatter) * dt;
          }
          T_full *= exp(-mp.sigma_t() * dt);
          T_red *= exp(-sigma_red * dt);
          tau_p += sigma_peak * dt;
          theta_p += sigma_theta * dt;
          tau_red += sigma_red * dt;
          {
            const double a = max_component(sigma_theta) * dt, tm = t + (0.5 - jitter) * dt;  // step midpoint
            m0 += a;
            m1 += a * tm;
            m2 += a * tm * tm;
          }
          return max_component(s_.light_side() ? T_full : T_red) > 1e-6;
        });
  // The environment behind the medium; its scattered light is in the grid. Camera side: its peak-scattered
  // light stays on the ray (smooth in angle), so it is attenuated by the reduced extinction only.
  if (ctx_.has_environment) L += (s_.light_side() ? T_full : T_red) * ctx_.environment;
  return L;
}

}  // namespace nimbus
