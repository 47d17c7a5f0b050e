// The ranks' parts made from a save file (BrickStep::split_from_file): rank 0 reads the balls'
// centres, decomposes them as a split does, then reads each array of the balls, the pairs and the
// wall contacts a piece at a time and sends each rank its rows of it, so that no rank holds the
// whole model, rank 0 included: each holds its part, and rank 0 a piece beside it.
#include "cycle/brick_step_parts.hpp"

#include <algorithm>
#include <cstring>
#include <numeric>
#include <stdexcept>
#include <type_traits>

#include <fmt/format.h>

#include "support/comm.hpp"
#include "support/peak_memory.hpp"

namespace trubal {

void BrickStep::split_from_file(const Model& full, TablePieces* file, bool results) {
  ++edition_;
  update_shares();   // (a collective call)
  const int ranks = team_->size(), me = team_->rank();
  const bool root = comm::root();
  const std::uint64_t kPiece = std::max<std::uint64_t>(1, policy_->save_piece_rows);   // (rows read at a time)
  const std::string doing =
      fmt::format("making its part of the decomposition from the save ({} balls in the whole model)", full.balls.size());
  together([&] {
    split_fault();
    if (root) decompose(full);
  }, doing);
  share_decomposition();
  std::vector<std::int64_t> counts(3, 0);
  if (root)
    for (PieceTable t : {PieceTable::Balls, PieceTable::Pairs, PieceTable::Walls})
      counts[static_cast<std::size_t>(t)] = static_cast<std::int64_t>(file->rows(t));
  comm::broadcast(counts);
  const std::vector<std::uint64_t> rows(counts.begin(), counts.end());
  const std::vector<std::uint32_t>& mine = rank_balls_[static_cast<std::size_t>(me)];
  if (rows[0] != full.balls.size()) throw std::logic_error("internal error: a save's balls differ from its model's");

  // Array k of a table, piece by piece: rank 0 reads the piece and sends each rank the rows `pick`
  // gives it (in order), which it appends to `v`; `got` on the others: how many come. (Rank 0's
  // buffers are kept from piece to piece: fresh ones would each be mapped and zeroed anew.)
  std::vector<char> raw;
  std::vector<std::vector<char>> out(static_cast<std::size_t>(ranks));
  const auto hand_out = [&](PieceTable table, std::size_t k, auto& v, std::uint64_t from, std::uint64_t count,
                            const std::vector<std::vector<std::uint32_t>>& pick, std::size_t got) {
    using T = typename std::decay_t<decltype(v)>::value_type;
    together([&] {
      if (!root) return;
      raw.resize(count * sizeof(T));
      file->read(table, k, from, count, raw.data(), sizeof(T));
      const T* piece = reinterpret_cast<const T*>(raw.data());
      for (int r = 0; r < ranks; ++r) {
        const std::vector<std::uint32_t>& rows_r = pick[static_cast<std::size_t>(r)];
        std::vector<char>& to = out[static_cast<std::size_t>(r)];
        to.resize(rows_r.size() * sizeof(T));
        T* o = reinterpret_cast<T*>(to.data());
        for (std::size_t q = 0; q < rows_r.size(); ++q) o[q] = piece[rows_r[q]];
      }
    }, doing);
    const std::size_t n = root ? out[0].size() / sizeof(T) : got;
    if (root)
      for (int r = 1; r < ranks; ++r)
        if (!out[static_cast<std::size_t>(r)].empty())
          comm::send_bytes(r, out[static_cast<std::size_t>(r)].data(), out[static_cast<std::size_t>(r)].size());
    if (n == 0) return;
    v.resize(v.size() + n);
    if (root) std::memcpy(v.data() + (v.size() - n), out[0].data(), n * sizeof(T));
    else comm::receive_bytes(0, v.data() + (v.size() - n), n * sizeof(T));
  };

  // The balls: each rank's rows in the whole model's order (rank_balls_ ascends).
  Balls& b = part_.balls;
  b.for_each_array([](auto& v) { std::decay_t<decltype(v)>().swap(v); });
  {
    std::vector<std::vector<std::uint32_t>> pick;
    each_piece_array(b, [&](auto& v, std::size_t k, bool) {
      v.reserve(mine.size());
      std::size_t next = 0;   // (mine's rows before the piece)
      for (std::uint64_t from = 0; from < rows[0]; from += kPiece) {
        const std::uint64_t count = std::min(kPiece, rows[0] - from);
        if (root) {
          pick.assign(static_cast<std::size_t>(ranks), {});
          for (std::uint64_t q = 0; q < count; ++q)
            pick[static_cast<std::size_t>(owner_[from + q])].push_back(static_cast<std::uint32_t>(q));
        }
        std::size_t end = next;
        while (end < mine.size() && mine[end] < from + count) ++end;
        hand_out(PieceTable::Balls, k, v, from, count, pick, end - next);
        next = end;
      }
    });
  }

  // The pairs and the wall contacts: rank 0 finds each row's ranks from its balls' owners (a
  // pair's two, a wall contact's one) and tells each rank its count of the piece's rows.
  const auto hand_out_table = [&](PieceTable table, auto& t, const std::vector<std::size_t>& ball_arrays, auto&& send) {
    const std::uint64_t n = rows[static_cast<std::size_t>(table)];
    std::vector<std::vector<std::uint32_t>> pick;
    std::vector<std::vector<std::uint32_t>> ends(ball_arrays.size());
    // Rank 0: each rank's rows of the piece [from, from + count).
    const auto pick_rows = [&](std::uint64_t from, std::uint64_t count) {
      pick.assign(static_cast<std::size_t>(ranks), {});
      for (std::size_t e = 0; e < ball_arrays.size(); ++e) {
        ends[e].resize(count);
        file->read(table, ball_arrays[e], from, count, ends[e].data(), sizeof(std::uint32_t));
      }
      for (std::uint64_t q = 0; q < count; ++q) {
        int last = -1;
        for (const auto& e : ends) {
          if (e[q] >= rows[0]) throw std::runtime_error("a contact of the save names no ball");
          const int r = owner_[e[q]];
          if (r != last) pick[static_cast<std::size_t>(r)].push_back(static_cast<std::uint32_t>(q));
          last = r;
        }
      }
    };
    // Each rank's count of rows first, that it holds its arrays at their length from the start.
    std::vector<std::int64_t> totals(static_cast<std::size_t>(ranks), 0);
    together([&] {
      if (!root) return;
      for (std::uint64_t from = 0; from < n; from += kPiece) {
        pick_rows(from, std::min(kPiece, n - from));
        for (int r = 0; r < ranks; ++r)
          totals[static_cast<std::size_t>(r)] += static_cast<std::int64_t>(pick[static_cast<std::size_t>(r)].size());
      }
    }, doing);
    comm::broadcast(totals);
    each_piece_array(t, [&](auto& v, std::size_t, bool used) {
      if (used && send(&v)) v.reserve(static_cast<std::size_t>(totals[static_cast<std::size_t>(me)]));
    });
    for (std::uint64_t from = 0; from < n; from += kPiece) {
      const std::uint64_t count = std::min(kPiece, n - from);
      together([&] {
        if (root) pick_rows(from, count);
      }, doing);
      std::size_t got = 0;
      if (root) {
        for (int r = 1; r < ranks; ++r) comm::send_word(r, static_cast<std::int64_t>(pick[static_cast<std::size_t>(r)].size()));
      } else {
        got = static_cast<std::size_t>(comm::receive_word(0));
      }
      each_piece_array(t, [&](auto& v, std::size_t k, bool used) {
        if (used && send(&v)) hand_out(table, k, v, from, count, pick, got);
      });
    }
  };
  ContactTable& c = file_pairs_;
  c = ContactTable{};
  c.set_history_laws(split_laws_);
  hand_out_table(PieceTable::Pairs, c, {0, 1}, [&](const void* v) { return results || c.result_index(v) < 0; });
  WallContacts& w = file_walls_;
  w = WallContacts{};
  hand_out_table(PieceTable::Walls, w, {0}, [](const void*) { return true; });

  together([&] {
    // The part: this rank's balls; its pairs and wall contacts wait for its first list.
    const std::size_t m = mine.size();
    bool whole = true;
    b.for_each_array([&](const auto& v) { whole = whole && v.size() == m; });
    if (!whole) throw std::logic_error("internal error: a rank's balls did not all come from the save");
    if (!results) c.drop_results();
    own_balls_alone(mine);
  }, doing);
  finish_part(full);
  from_file_ = true;
  from_file_results_ = results;
  return_free_memory();
}

}  // namespace trubal
