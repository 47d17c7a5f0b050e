// The wall-contact loops, with and without details.
#include "cycle/kernel_walls.hpp"

namespace trubal::loops {
namespace {

template <std::size_t... I>
constexpr std::array<WallLoop, sizeof...(I)> wall_table(std::index_sequence<I...>) {
  return {&wall_loop<ContactFeatures::from_index(0 + I)>...};
}
constexpr auto kTable = wall_table(std::make_index_sequence<ContactFeatures::kCount>{});

}  // namespace

WallLoop wall_loop_at(unsigned i) { return kTable.at(i - 0); }

}  // namespace trubal::loops
