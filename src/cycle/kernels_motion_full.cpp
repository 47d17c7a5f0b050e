// The law-of-motion loops that write each ball's forces (what measurements read).
#include "cycle/kernel_motion.hpp"

namespace trubal::loops {
namespace {

template <std::size_t... I>
constexpr std::array<MotionLoop, sizeof...(I)> motion_table(std::index_sequence<I...>) {
  return {&motion_loop<MotionFeatures::from_index(MotionFeatures::kCount / 2 + I)>...};
}
constexpr auto kTable = motion_table(std::make_index_sequence<MotionFeatures::kCount / 2>{});

}  // namespace

MotionLoop motion_loop_full(unsigned i) { return kTable.at(i - MotionFeatures::kCount / 2); }

}  // namespace trubal::loops
