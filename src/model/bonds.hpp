// The parallel bonds (BOND; physics/bond.hpp, doc/physics.md "Parallel bonds"): a table of their
// own, not contacts found by proximity. A bond is keyed by its two balls' ids (id_i < id_j), so that
// a new pair list, a renumbering or another storage order cannot confuse it. Its rows are in no fixed
// order: the step keeps them in its own (by the balls' places in memory, cycle/bond_pass.hpp), and
// whatever shows, saves or sums them goes by (id_i, id_j) (bond_rows_by_id): the one order in which
// every ball sums its bonds, whatever the backend, and in which they are listed and saved.
// A broken bond stays in the table (PRINT bonds says why it broke, DUMP draws it as a crack) and
// carries no force: its pair is an ordinary contact.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace trubal {

// A number no table of bonds has had before in this process (model/bond_table.cpp).
std::uint64_t next_bonds_edition();

// The edition of a table of bonds: a number of its own, new with every edit of the table (changed())
// and with every copy, so that what is indexed by a table (the step's, cycle/bond_pass.hpp) knows it
// in one comparison, without reading its rows: a table restored from a copy (a step taken again, a
// rescue) is a new edition, as is one read from a file or handed over between the members of a
// spatial decomposition.
class BondsEdition {
 public:
  BondsEdition() : value_(next_bonds_edition()) {}
  BondsEdition(const BondsEdition&) : value_(next_bonds_edition()) {}
  BondsEdition& operator=(const BondsEdition&) { value_ = next_bonds_edition(); return *this; }
  std::uint64_t value() const { return value_; }
  void renew() { value_ = next_bonds_edition(); }

 private:
  std::uint64_t value_;
};

struct Bonds {
  std::vector<std::int64_t> id_i, id_j;                 // the balls' ids, id_i < id_j
  // The law of each bond (BOND's words): stiffness per area, strengths, tan of the friction angle,
  // the bond's radius and its moment contribution factor.
  std::vector<double> kn, ks, tension, cohesion, tan_friction, radius, mcf;
  // The state: forces and moments on ball j (physics/bond.hpp BondState); a broken bond keeps the
  // values that broke it.
  std::vector<double> fn, fsx, fsy, fsz, mt, mbx, mby, mbz;
  std::vector<std::uint8_t> fate;                       // physics/bond.hpp BondFate: 0 intact, 1, 2 broken

  // Every edit of the table's rows (which bonds, their order, their law; not the state a step
  // writes, nor a bond breaking in a step) calls changed(): BOND, BOND delete, DELETE, RENUMBER,
  // a file read, a hand-over between members. A copy is a new edition by itself.
  BondsEdition edition;
  void changed() { edition.renew(); }

  std::size_t size() const { return id_i.size(); }
  bool empty() const { return id_i.empty(); }
  // Every per-bond array, so that resizing, reordering and SAVE cannot miss one.
  template <class F> void for_each_array(F&& f) {
    f(id_i); f(id_j);
    for (auto* v : {&kn, &ks, &tension, &cohesion, &tan_friction, &radius, &mcf, &fn, &fsx, &fsy, &fsz, &mt, &mbx,
                    &mby, &mbz})
      f(*v);
    f(fate);
  }
  // The arrays that are vectors on j, which change sign when i and j trade places (RENUMBER): the
  // shear force and the bending moment. (Fn and Mt about n keep theirs: n turns round too.)
  template <class F> void for_each_swapped(F&& f) {
    for (auto* v : {&fsx, &fsy, &fsz, &mbx, &mby, &mbz}) f(*v);
  }
};

}  // namespace trubal
