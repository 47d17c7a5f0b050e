// The messages of a rebuild on the parts: what leaves with a ball that changes owner (its pairs,
// wall contacts and bonds), the counts and the records each member sends (Travels, brick_step_parts.hpp),
// and what arrives.
#include "cycle/brick_step_parts.hpp"

#include <algorithm>

#include "model/edit.hpp"

namespace trubal {

void BrickStep::find_leaving(Rebuild& r) const {
  // A moving ball's pairs and wall contacts (this rank's part holds all of them), to its new owner;
  // a pair of two balls moving to two ranks, to both.
  r.pair_rows.assign(r.ranks, {});
  r.wall_rows.assign(r.ranks, {});
  r.bond_rows.assign(r.ranks, {});
  if (r.moved == 0) return;
  r.part_dest.assign(part_.balls.size(), -1);
  for (std::size_t q = 0; q < owned_.size(); ++q)
    if (r.dest[q] != r.me) r.part_dest[owned_[q]] = r.dest[q];
  const ContactTable& c = part_.contacts;
  for (std::size_t p = 0; p < c.size(); ++p) {
    const int di = r.part_dest[c.i[p]], dj = r.part_dest[c.j[p]];
    for (int d : {di, dj != di ? dj : -1})
      if (d >= 0) r.pair_rows[d].push_back(static_cast<std::uint32_t>(p));
  }
  const WallContacts& w = part_.wall_contacts;
  for (std::size_t q = 0; q < w.size(); ++q) {
    const int d = r.part_dest[w.ball[q]];
    if (d >= 0) r.wall_rows[d].push_back(static_cast<std::uint32_t>(q));
  }
  // Its bonds, broken or not (the part holds every bond of its owned balls), as its pairs.
  const Bonds& t = part_.bonds;
  for (std::size_t q = 0; q < t.size(); ++q) {
    const std::int64_t i = find_ball(part_, t.id_i[q]), j = find_ball(part_, t.id_j[q]);
    const int di = i >= 0 ? r.part_dest[static_cast<std::size_t>(i)] : -1;
    const int dj = j >= 0 ? r.part_dest[static_cast<std::size_t>(j)] : -1;
    for (int d : {di, dj != di ? dj : -1})
      if (d >= 0) r.bond_rows[d].push_back(static_cast<std::uint32_t>(q));
  }
}

void BrickStep::announce_counts(Rebuild& r) const {
  // To each rank, how many balls, pairs and wall contacts this one sends it.
  r.out.assign(r.ranks, {});
  r.in.assign(r.ranks, {});
  for (int q = 0; q < r.ranks; ++q) {
    r.out[q] = {static_cast<double>(r.shell[q].size()), static_cast<double>(r.pair_rows[q].size()),
                static_cast<double>(r.wall_rows[q].size()), static_cast<double>(r.bond_rows[q].size())};
    r.in[q].assign(4, 0.0);
  }
}

bool BrickStep::shells_within_bounds(Rebuild& r) {
  // What each rank sends here, from the counts it announced; false where the parts are to be made
  // afresh instead (a collective call).
  r.shell_in.assign(r.ranks, 0);
  r.in_pairs.assign(r.ranks, 0);
  r.in_walls.assign(r.ranks, 0);
  r.in_bonds.assign(r.ranks, 0);
  for (int q = 0; q < r.ranks; ++q) {
    r.received += r.in[q][0];
    r.shell_in[q] = static_cast<std::size_t>(r.in[q][0]);
    r.in_pairs[q] = static_cast<std::size_t>(r.in[q][1]);
    r.in_walls[q] = static_cast<std::size_t>(r.in[q][2]);
    r.in_bonds[q] = static_cast<std::size_t>(r.in[q][3]);
  }
  // The balls have spread where the largest shell has grown past twice what it was at the first
  // rebuild after the split: the parts are made afresh (and balanced) from the whole model.
  std::vector<double> most{r.received};
  team_->max_all(most);
  if (shell_base_ == 0) shell_base_ = std::max(most[0], 1.0);
  else if (most[0] > 2 * shell_base_) return false;
  return true;
}

void BrickStep::pack_messages(Rebuild& r) const {
  // To each rank, the records of the balls of its shell, then those of the moving balls' pairs and
  // wall contacts (Travels); and room for what it sends here.
  const std::size_t words = record_words<Balls>(), pair_words = record_words(part_.contacts),
                    wall_words = record_words<WallContacts>(), bond_words = record_words<Bonds>();
  for (int q = 0; q < r.ranks; ++q) {
    const std::vector<std::uint32_t>& shell = r.shell[q];
    std::vector<double>& out = r.out[q];
    const std::size_t count = shell.size(), pairs = r.pair_rows[q].size(), walls = r.wall_rows[q].size(),
                      bonds = r.bond_rows[q].size();
    out.assign(words * count + pair_words * pairs + wall_words * walls + bond_words * bonds, 0.0);
    for (std::size_t t = 0; t < count; ++t) {
      const std::uint32_t k = shell[t];
      out[t * words + Travels<Balls>::kIndex] = global_ball_[k];
      out[t * words + Travels<Balls>::kOwner] = r.part_dest.empty() || r.part_dest[k] < 0 ? r.me : r.part_dest[k];
    }
    double* const pairs_at = out.data() + words * count;
    pack_records(part_.balls, shell, global_ball_, out.data());
    pack_records(part_.contacts, r.pair_rows[q], global_ball_, pairs_at);
    pack_records(part_.wall_contacts, r.wall_rows[q], global_ball_, pairs_at + pair_words * pairs);
    pack_records(part_.bonds, r.bond_rows[q], global_ball_, pairs_at + pair_words * pairs + wall_words * walls);
    std::vector<std::uint32_t>().swap(r.pair_rows[q]);
    std::vector<std::uint32_t>().swap(r.wall_rows[q]);
    std::vector<std::uint32_t>().swap(r.bond_rows[q]);
    r.in[q].assign(words * r.shell_in[q] + pair_words * r.in_pairs[q] + wall_words * r.in_walls[q] +
                       bond_words * r.in_bonds[q],
                   0.0);
  }
}

void BrickStep::list_entries(Rebuild& r) const {
  // This rank's balls and those received (their records' heads), in the whole model's order.
  const std::size_t words = record_words<Balls>();
  r.entries.reserve(owned_.size() + static_cast<std::size_t>(r.received));
  for (std::size_t q = 0; q < owned_.size(); ++q)
    r.entries.push_back({global_ball_[owned_[q]], -1, owned_[q], r.dest[q]});
  for (int q = 0; q < r.ranks; ++q)
    for (std::size_t t = 0; t < r.shell_in[q]; ++t) {
      const double* head = r.in[q].data() + t * words;
      r.entries.push_back({static_cast<std::uint32_t>(head[Travels<Balls>::kIndex]), q, static_cast<std::uint32_t>(t),
                           static_cast<int>(head[Travels<Balls>::kOwner])});
    }
  std::sort(r.entries.begin(), r.entries.end(),
            [](const Rebuild::Entry& p, const Rebuild::Entry& q) { return p.global < q.global; });
}

void BrickStep::unpack_arrivals(Rebuild& r) const {
  // The history records of the balls that move to this rank: their pairs (in the whole model's
  // numbers) and their wall contacts, after the balls in each rank's message.
  const std::size_t words = record_words<Balls>(), pair_words = record_words(part_.contacts),
                    wall_words = record_words<WallContacts>(), bond_words = record_words<Bonds>();
  for (int q = 0; q < r.ranks; ++q) {
    const double* rec = r.in[q].data() + words * r.shell_in[q];
    if (r.in_pairs[q] > 0) r.arrived_pairs.set_history_laws(part_.contacts.history_laws);   // (as pair_words)
    for (std::size_t t = 0; t < r.in_pairs[q]; ++t, rec += pair_words) unpack_record(rec, r.arrived_pairs);
    for (std::size_t t = 0; t < r.in_walls[q]; ++t, rec += wall_words) unpack_record(rec, r.arrived_walls);
    for (std::size_t t = 0; t < r.in_bonds[q]; ++t, rec += bond_words) unpack_record(rec, r.arrived_bonds);
  }
}

}  // namespace trubal
