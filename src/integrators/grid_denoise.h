// The scatter grid's photon noise filtered where it is noise (issue 12).
//
// A photon grid's node holds the light of the photons that passed near it; at the photon counts that pay
// at small image sizes that noise is most of `mfs`'s error (docs/benchmarks.md, "The scatter grid
// denoised"). Smoothing the nodes lowers the noise and blurs the light's real structure (a lit rim, a
// shadow's edge) as much. The photons come in kPhotonBatches independent batches, so each node's noise is
// known: per node inside the media, the difference d = v - s of its value v from its smoothed value s is
// kept in the share D / (D + V) (a Wiener filter), V the variance of d from the batches' spread and D the
// power of the real structure in d, the mean of d^2 less V over the node's 3 x 3 x 3 neighbourhood (V
// there too). Where d is noise the node takes s, where it is structure v; the more photons, the less the
// filter changes. s: kDenoisePasses along each axis of the 5-node quadratic Savitzky-Golay filter
// (-3, 12, 17, 12, -3) / 35, at the nodes whose 4 neighbours along the axis are inside the media (the
// others keep their values along it). It leaves any quadratic field as it is, so the curvature of the
// light (the grid's structure below the noise of one node, which adds up over an image) is not blurred:
// a binomial smoothing ([1 4 6 4 1] / 16, the beam grid's) darkened the thin media's images and the
// side-lit sphere's where this one does not (docs/benchmarks.md, "The scatter grid denoised").
#pragma once

#include <vector>

#include "core/node_grid.h"
#include "core/zeroed_floats.h"

namespace nimbus {

inline constexpr int kDenoisePasses = 8;  // passes of the quadratic smoothing filter along each axis

// values: floats per node (node n at [n floats, (n + 1) floats)). per_batch: per node, per batch
// (`batches`), per probe, that batch's share of the node's value probes[p] (a float index within a node):
// what trace_photons_folded keeps. The same share D / (D + V) (d^2 and V summed over the probes) applies to
// every float of the node. inside: per node, nonzero where a medium is (the others keep their values and
// are left out of their neighbours' smoothing). Nothing changes where the sizes do not match. The result
// does not depend on the thread count.
void denoise_grid(FloatArray* values, const NodeGrid& grid, int floats, const FloatArray& per_batch,
                  int batches, const std::vector<int>& probes, const std::vector<uint8_t>& inside);

}  // namespace nimbus
