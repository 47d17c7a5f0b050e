// TRUBAL's own way: space cut into boxes, balls hung on linked lists per box, a candidate pair
// list with a skin (Verlet) rebuilt only when some ball has moved half the skin.
#pragma once

#include <memory>

#include "backends/backend.hpp"

namespace trubal {

std::unique_ptr<Backend> make_serial_backend();

}  // namespace trubal
