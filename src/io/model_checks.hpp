// What must hold of a model for it to run, where a checksum cannot vouch for it (a save written by
// hand or by another program): RESTART refuses one that fails.
#pragma once

#include <string>

#include "model/model.hpp"

namespace trubal {

// "" when the model holds together, else what does not.
std::string invalid_model(const Model& m);

}  // namespace trubal
