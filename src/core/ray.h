// A ray o + t d (d a unit vector, t in scene lengths): what the driver hands an integrator.
#pragma once

#include "core/math.h"

namespace nimbus {

struct Ray {
  Vec3 o;  // origin
  Vec3 d;  // unit direction of travel
};

}  // namespace nimbus
