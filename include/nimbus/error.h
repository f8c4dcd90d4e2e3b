// nimbus::Error: the one exception type the library throws. Messages carry their context
// ("scene.json: /media/0/sigma_s: must be >= 0"); only apps/ prints them and exits.
#pragma once

#include <stdexcept>
#include <string>

namespace nimbus {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Thrown when a render or simulation is cancelled through its callback.
class Cancelled : public Error {
 public:
  Cancelled() : Error("cancelled") {}
};

}  // namespace nimbus
