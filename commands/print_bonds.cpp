// PRINT bonds: the parallel bonds' table, to the screen or a CSV file (commands/print.cpp dispatches).
#include <cmath>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "commands/print_parts.hpp"
#include "io/atomic_file.hpp"
#include "io/csv.hpp"
#include "model/bond_table.hpp"
#include "model/edit.hpp"
#include "physics/bond.hpp"
#include "support/comm.hpp"

namespace trubal {

namespace {

const char* fate_name(std::uint8_t fate) {
  return fate == static_cast<std::uint8_t>(BondFate::Tension) ? "tension"
         : fate == static_cast<std::uint8_t>(BondFate::Shear) ? "shear"
                                                               : "intact";
}

}  // namespace

void print_bonds(Context& ctx, const Range& range, const std::string& file) {
  // (Without a range, the table and the balls' ids alone: under mpirun the parts' bonds gathered
  // into rank 0's table, no whole model; a range reads the balls.)
  const Model& m = range.empty() ? ctx.session.model_for_bonds() : ctx.session.model();
  const Bonds& t = m.bonds;
  std::vector<bool> in(m.balls.size(), range.empty());
  if (!range.empty())
    for (auto k : ctx.session.select(range)) in[k] = true;
  std::vector<std::size_t> rows;
  for (std::size_t q : bond_rows_by_id(t)) {
    const std::int64_t i = find_ball(m, t.id_i[q]), j = find_ball(m, t.id_j[q]);
    if ((i >= 0 && in[static_cast<std::size_t>(i)]) || (j >= 0 && in[static_cast<std::size_t>(j)])) rows.push_back(q);
  }
  if (!comm::root()) return;   // (rank 0 writes, as print_balls)
  // A broken bond shows the forces and stresses that broke it.
  if (!file.empty()) {
    write_file_atomically(file, [&](std::ostream& csv) {
      csv << "i,j,radius,fn,fsx,fsy,fsz,mt,mbx,mby,mbz,sigma,tau,strength_t,strength_s,state\n";
      for (std::size_t q : rows) {
        const BondLaw law = bond_law(t, q);
        const BondStress s = bond_stress(law, bond_state(t, q));
        csv << t.id_i[q] << ',' << t.id_j[q];
        for (double v : {t.radius[q], t.fn[q], t.fsx[q], t.fsy[q], t.fsz[q], t.mt[q], t.mbx[q], t.mby[q], t.mbz[q], s.sigma,
                         s.tau, law.tension, bond_shear_strength(law, s.sigma_n)})
          csv << ',' << csv_real(v);
        csv << ',' << fate_name(t.fate[q]) << '\n';
      }
    });
    ctx.out << fmt::format("{} written to {}\n", count_of(rows.size(), "bond"), file);
    return;
  }
  ctx.out << fmt::format("{:>8} {:>8} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11} {:>8}\n", "i", "j", "fn", "|fs|", "|mt|",
                         "|mb|", "sigma", "tau", "state");
  for (std::size_t q : rows) {
    const BondStress s = bond_stress(bond_law(t, q), bond_state(t, q));
    const double fs = std::sqrt(t.fsx[q] * t.fsx[q] + t.fsy[q] * t.fsy[q] + t.fsz[q] * t.fsz[q]);
    const double mb = std::sqrt(t.mbx[q] * t.mbx[q] + t.mby[q] * t.mby[q] + t.mbz[q] * t.mbz[q]);
    ctx.out << fmt::format("{:>8} {:>8} {:>11.4g} {:>11.4g} {:>11.4g} {:>11.4g} {:>11.4g} {:>11.4g} {:>8}\n", t.id_i[q],
                           t.id_j[q], t.fn[q], fs, std::abs(t.mt[q]), mb, s.sigma, s.tau, fate_name(t.fate[q]));
  }
}

}  // namespace trubal
