// TRUBAL's own way of finding pairs: space cut into boxes, balls hung on linked lists per box
// (backends/serial/box_grid.hpp); in a periodic cell the shared periodic search. One thread.
#pragma once

#include <memory>

#include "backends/backend.hpp"

namespace trubal {

std::unique_ptr<Backend> make_serial_backend();

}  // namespace trubal
