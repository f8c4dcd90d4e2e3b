// The value types of the public API: positions and directions (Vec3), linear RGB (Rgb). Both are
// Imath's V3d, the type OpenEXR and OpenVDB users already know.
#pragma once

#include <Imath/ImathVec.h>

namespace nimbus {

using Vec3 = Imath::V3d;
using Rgb = Imath::V3d;  // linear RGB radiance or per-channel coefficients

}  // namespace nimbus
