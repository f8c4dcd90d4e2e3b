// Phase functions: a closed set dispatched through std::variant.
// Convention: every function takes cos_theta = dot(wi, wo) of the PROPAGATION directions before and
// after the scatter (cos_theta = 1 is no deflection), and is a density per steradian normalised on the
// sphere. sample() returns a propagation direction with pdf == eval (all are sampled exactly).
#pragma once

#include <string>
#include <variant>
#include <vector>

#include "core/math.h"
#include "nimbus/phase.h"

namespace nimbus {

// --- Physics as free functions, tested alone --------------------------------------------------
double hg_eval(double cos_theta, double g);
// cos_theta distributed as HG(g), from u in [0, 1).
double hg_sample_cos(double u, double g);
// <theta^2> per component of the small-angle expansion Z(p) ~ 1 - theta2 p^2 / 2 is infinite for HG
// (its forward peak is Cauchy-like, ../shared/notes/mfs-math.md); these are the usual stand-ins.
double hg_theta2_one_minus_g(double g);         // (1 - g)
double hg_theta2_one_minus_g2_over3(double g);  // (1 - g^2) / 3

// The phase function structs (IsotropicPhase ... TabulatedPhase, Phase) are in nimbus/phase.h.

GaussPhase make_gauss_phase(double theta2);
// Normalises `value`; throws nimbus::Error on a malformed table.
TabulatedPhase make_tabulated_phase(std::string name, std::vector<double> theta, std::vector<double> value);

double phase_eval(const Phase& phase, double cos_theta);
// Samples a propagation direction after scattering from propagation direction wi.
Vec3 phase_sample(const Phase& phase, const Vec3& wi, double u1, double u2);
// Mean cosine <cos theta> of the phase function.
double phase_mean_cosine(const Phase& phase);
// A short human-readable description ("hg(g=0.85)").
std::string phase_describe(const Phase& phase);

}  // namespace nimbus
