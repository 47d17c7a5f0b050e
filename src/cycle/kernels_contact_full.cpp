// The contact loops with details (what measurements read: normal, overlap, forces, state).
#include "cycle/kernel_contacts.hpp"

namespace trubal::loops {
namespace {

template <std::size_t... I>
constexpr std::array<ContactLoop, sizeof...(I)> contact_table(std::index_sequence<I...>) {
  return {&contact_loop<ContactFeatures::from_index(ContactFeatures::kCount / 2 + I)>...};
}
constexpr auto kTable = contact_table(std::make_index_sequence<ContactFeatures::kCount / 2>{});

}  // namespace

ContactLoop contact_loop_full(unsigned i) { return kTable.at(i - ContactFeatures::kCount / 2); }

}  // namespace trubal::loops
