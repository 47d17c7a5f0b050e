// The cross loops (pairs whose lower ball another thread owns); never with details.
#include "cycle/kernel_contacts.hpp"

namespace trubal::loops {
namespace {

template <std::size_t... I>
constexpr std::array<CrossLoop, sizeof...(I)> cross_table(std::index_sequence<I...>) {
  return {&cross_loop<ContactFeatures::from_index(0 + I)>...};
}
constexpr auto kTable = cross_table(std::make_index_sequence<ContactFeatures::kCount / 2>{});

}  // namespace

CrossLoop cross_loop_at(unsigned i) { return kTable.at(i - 0); }

}  // namespace trubal::loops
