// SAVE/RESTART: the whole model (balls, materials, contacts with their shear history, space,
// settings, energy, groups) in a versioned binary file with a checksum, written atomically.
#pragma once

#include <string>

#include "model/model.hpp"

namespace trubal {

// Writes to PATH.tmp-PID, syncs, renames over PATH. Throws std::runtime_error on failure (the old
// file, if any, is untouched).
void save_model(const Model& model, const std::string& path);
// Reads a file written by save_model. Throws std::runtime_error for a missing, truncated,
// corrupted or foreign file, or one of another version; the model is not touched then.
Model load_model(const std::string& path);

}  // namespace trubal
