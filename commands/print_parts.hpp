// PRINT's items kept in files of their own (commands/print_info.cpp, commands/print_tables.cpp);
// commands/print.cpp reads the arguments and calls them.
#pragma once

#include <string>

#include "commands/common.hpp"

namespace trubal {

void print_info(Context& ctx);
void print_counters(Context& ctx, const std::string& file);
void print_balls(Context& ctx, const Range& range, const std::string& file);
void print_contacts(Context& ctx, const Range& range, const std::string& file);
void print_bonds(Context& ctx, const Range& range, const std::string& file);   // commands/print_bonds.cpp
void print_walls(Context& ctx, const std::string& file);
void print_psd(Context& ctx, const std::string& file);

}  // namespace trubal
