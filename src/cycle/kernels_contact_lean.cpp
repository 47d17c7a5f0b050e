// The contact loops without details (what a plain step computes).
#include "cycle/kernel_contacts.hpp"

namespace trubal::loops {
namespace {

template <std::size_t... I>
constexpr std::array<ContactLoop, sizeof...(I)> contact_table(std::index_sequence<I...>) {
  return {&contact_loop<ContactFeatures::from_index(0 + I)>...};
}
constexpr auto kTable = contact_table(std::make_index_sequence<ContactFeatures::kCount / 2>{});

}  // namespace

ContactLoop contact_loop_lean(unsigned i) { return kTable.at(i - 0); }

}  // namespace trubal::loops
