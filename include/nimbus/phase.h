// Phase functions as a scene describes them: a closed set of plain structs in one std::variant.
// Evaluation and sampling live in the library (src/media/phase.h); docs/scene-format.md documents the
// JSON.
#pragma once

#include <string>
#include <variant>
#include <vector>

namespace nimbus {

struct IsotropicPhase {};
struct HgPhase {
  double g = 0.0;
};
struct DoubleHgPhase {
  double g1 = 0.0, g2 = 0.0, w = 1.0;  // w HG(g1) + (1 - w) HG(g2)
};
// A Gaussian forward peak exp(-theta^2 / (2 theta2)) normalised on the sphere; theta2 is the
// per-component mean square deflection of seed eq. 5 (validation of the MFS kernel).
struct GaussPhase {
  double theta2 = 0.01;
  double norm = 0.0;  // 1 / integral over the sphere; filled by make_gauss_phase
};
// A phase function tabulated against polar angle, linear in theta between nodes (Mie tables).
struct TabulatedPhase {
  std::string name;
  std::vector<double> theta;  // radians, theta[0] = 0 ... theta.back() = pi, increasing
  std::vector<double> value;  // density per sr (normalised by make_tabulated_phase)
  std::vector<double> cdf;    // cumulative probability at each node
};

using Phase = std::variant<IsotropicPhase, HgPhase, DoubleHgPhase, GaussPhase, TabulatedPhase>;

}  // namespace nimbus
