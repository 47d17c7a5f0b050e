// The kept parts' state streamed to rank 0 in the whole model's order a chunk at a time (SAVE where
// rank 0's whole model is hollow: io/save.hpp's StateSource), so that rank 0 holds a chunk of an
// array, not the model.
//
// Each member's entries of a table (its own balls; the pairs whose ball i it owns; its balls' wall
// contacts) keep the whole model's order among themselves (a part is numbered in that order and its
// lists follow it), so their places in the whole order are ascending on each member. A chunk of the
// whole order is then a run of each member's entries: each member sends its run, with the places,
// and rank 0 sets them in place. The pairs' and wall contacts' places are counted first: in the
// whole order they go by ball i (or ball), whose owner holds all of them, so a ball's first place
// is the count of the entries of the balls before it, summed over the members a chunk of balls at a
// time (place_by_ball).
#include "cycle/brick_step_parts.hpp"

#include <bit>
#include <exception>
#include <stdexcept>

#include "model/dump_rows.hpp"
#include "model/periodic_cell.hpp"
#include "support/comm.hpp"

namespace trubal {
namespace {

// Entries of the whole order a chunk streams, and balls a chunk of place_by_ball counts: rank 0's
// buffers of a chunk hold a few MiB.
constexpr std::size_t kChunk = std::size_t{1} << 18;

// A value as it travels: integers of 32 bits and fewer by value (exact in a double), 64-bit ones by
// their bits (io/save.cpp's write_streamed reads them back alike).
template <class T> double to_wire(T v) {
  if constexpr (sizeof(T) == 8 && std::is_integral_v<T>) return std::bit_cast<double>(v);
  else return static_cast<double>(v);
}

}  // namespace

template <class Value>
void BrickStep::stream_in_order(const std::vector<std::uint64_t>& at, std::uint64_t total, Value&& value,
                                const std::function<void(const std::vector<double>&)>& write) {
  std::size_t q = 0;   // this member's next entry
  std::vector<double> out, in, chunk;
  std::exception_ptr failed;   // (rank 0's writing: every member streams on to the end all the same)
  for (std::uint64_t a = 0; a < total; a += kChunk) {
    const std::uint64_t b = std::min<std::uint64_t>(total, a + kChunk);
    together([&] {
      out.clear();
      for (; q < at.size() && at[q] < b; ++q) {
        out.push_back(static_cast<double>(at[q] - a));
        out.push_back(value(q));
      }
    }, "streaming its part to rank 0");
    comm::gather_to_root(out, in);
    if (!comm::root() || failed) continue;
    try {
      chunk.assign(b - a, 0.0);
      for (std::size_t e = 0; e + 1 < in.size(); e += 2) chunk[static_cast<std::size_t>(in[e])] = in[e + 1];
      write(chunk);
    } catch (...) {
      failed = std::current_exception();
    }
  }
  if (failed) std::rethrow_exception(failed);
}

std::uint64_t BrickStep::place_by_ball(const std::vector<std::uint32_t>& ball, std::vector<std::uint64_t>& at) {
  // Every member's count of entries per ball of a chunk of balls, to every member; each member's
  // entries' places follow from the counts of the balls before theirs.
  std::uint64_t base = 0;   // the entries of the balls before the chunk, over every member
  std::size_t q = 0;
  std::vector<double> mine, all;
  std::vector<std::uint64_t> first;   // the chunk's balls' first places
  together([&] { at.assign(ball.size(), 0); }, "placing its part's entries");
  for (std::uint64_t a = 0; a < full_balls_ || a == 0; a += kChunk) {
    const std::uint64_t b = std::min<std::uint64_t>(full_balls_, a + kChunk);
    const std::size_t from = q;
    together([&] {
      mine.clear();
      for (; q < ball.size() && ball[q] < b; ++q) {
        if (mine.empty() || mine[mine.size() - 2] != static_cast<double>(ball[q] - a)) {
          mine.push_back(static_cast<double>(ball[q] - a));
          mine.push_back(0);
        }
        mine.back() += 1;
      }
    }, "placing its part's entries");
    comm::allgather(mine, all);
    together([&] {
      first.assign(b - a + 1, 0);
      for (std::size_t e = 0; e + 1 < all.size(); e += 2) first[static_cast<std::size_t>(all[e]) + 1] += static_cast<std::uint64_t>(all[e + 1]);
      first[0] = base;
      for (std::size_t k = 1; k < first.size(); ++k) first[k] += first[k - 1];
      for (std::size_t e = from, run = 0; e < q; ++e) {
        run = e > from && ball[e] == ball[e - 1] ? run + 1 : 0;
        at[e] = first[ball[e] - a] + run;
      }
      base = first.back();
    }, "placing its part's entries");
    if (b == full_balls_) break;
  }
  return base;
}

std::uint64_t BrickStep::place_saved_pairs(bool results) {
  if (!live_ || team_->shares_whole()) throw std::logic_error("internal error: pairs placed where no rank's part is live");
  const ContactTable& c = part_.contacts;
  std::vector<std::uint32_t> ball;
  together([&] { results_fault(); }, "gathering the contact results from the parts");
  together([&] {
    saved_pairs_.clear();
    const bool touched = results && c.results_kept();
    for (std::uint32_t q : owned_pairs_)
      if ((touched && c.state[q] != 0) || c.has_history(q)) {
        saved_pairs_.push_back(q);
        ball.push_back(global_ball_[c.i[q]]);
      }
  }, "placing its part's pairs");
  return saved_pairs_total_ = place_by_ball(ball, saved_pair_at_);
}

std::uint64_t BrickStep::place_saved_walls() {
  if (!live_ || team_->shares_whole()) throw std::logic_error("internal error: wall contacts placed where no rank's part is live");
  std::vector<std::uint32_t> ball;
  together([&] {
    for (std::uint32_t q : owned_walls_) ball.push_back(global_ball_[part_.wall_contacts.ball[q]]);
  }, "placing its part's wall contacts");
  return saved_walls_total_ = place_by_ball(ball, saved_wall_at_);
}

void BrickStep::free_saved() {
  auto free = [](auto& v) { std::decay_t<decltype(v)>().swap(v); };
  free(saved_pairs_); free(saved_pair_at_); free(saved_wall_at_);
  saved_pairs_total_ = saved_walls_total_ = 0;
}

void BrickStep::stream_table(int table, std::size_t k, const std::function<void(const std::vector<double>&)>& write) {
  if (!live_ || team_->shares_whole()) throw std::logic_error("internal error: a table streamed where no rank's part is live");
  std::size_t seen = 0;
  bool done = false;
  // Array k of `t`'s list, declared history and results (io/save.cpp's order), over `rows` at `at`;
  // ball_a, ball_b: the arrays of the part's balls' indices, sent as the whole model's.
  auto each = [&](auto& t, const std::vector<std::uint32_t>& rows, const std::vector<std::uint64_t>& at, std::uint64_t total,
                  const void* ball_a, const void* ball_b) {
    auto visit = [&](const auto& v) {
      if (seen++ != k) return;
      done = true;
      const bool balls = static_cast<const void*>(&v) == ball_a || static_cast<const void*>(&v) == ball_b;
      stream_in_order(at, total, [&](std::size_t q) -> double {
        const std::size_t r = rows[q];
        if (r >= v.size()) return 0.0;   // (a part not in use, or results not kept: zero)
        if (balls) return static_cast<double>(global_ball_[static_cast<std::size_t>(v[r])]);
        return to_wire(v[r]);
      }, write);
    };
    t.for_each_list_array(visit);
    t.for_each_declared_history([&](const auto& v, const HistoryPart&, bool) { visit(v); });
    t.for_each_result_array(visit);
  };
  if (table == 0) {
    // The balls' array k of Balls::for_each_array.
    std::vector<std::uint64_t> at;
    together([&] { for (std::uint32_t q : owned_) at.push_back(global_ball_[q]); }, "streaming its part to rank 0");
    part_.balls.for_each_array([&](const auto& v) {
      if (seen++ != k) return;
      done = true;
      stream_in_order(at, full_balls_, [&](std::size_t q) { return to_wire(v[owned_[q]]); }, write);
    });
  } else if (table == 1) {
    each(part_.contacts, saved_pairs_, saved_pair_at_, saved_pairs_total_, &part_.contacts.i, &part_.contacts.j);
  } else {
    each(part_.wall_contacts, owned_walls_, saved_wall_at_, saved_walls_total_, &part_.wall_contacts.ball, nullptr);
  }
  if (!done) throw std::logic_error("internal error: an array the table does not have");
}

void BrickStep::merge_rows_to_root(std::size_t count, std::size_t width, const std::function<void(std::size_t, double*)>& row,
                                   const std::function<bool(const double*, const double*)>& before,
                                   const std::function<void(const double*)>& take) {
  constexpr std::size_t kBatch = 4096;   // rows a message
  const int ranks = team_->size();
  if (!comm::root()) {
    // A batch of rows in order each time rank 0 asks; the last one short (empty where the rows
    // fill whole batches).
    std::vector<double> batch;
    for (std::size_t q = 0;;) {
      comm::receive_word(0);
      const std::size_t n = std::min(kBatch, count - q);
      batch.resize(n * width);
      for (std::size_t e = 0; e < n; ++e) row(q + e, batch.data() + e * width);
      q += n;
      comm::send_word(0, static_cast<std::int64_t>(n));
      if (n > 0) comm::send_bytes(0, batch.data(), n * width * sizeof(double));
      if (n < kBatch) return;
    }
  }
  // Rank 0: each rank's batch, the next of its rows there, and whether more batches follow.
  struct Source {
    std::vector<double> rows;
    std::size_t head = 0, n = 0, next = 0;   // (next: rank 0's own next row)
    bool more = true;
  };
  std::vector<Source> from(static_cast<std::size_t>(ranks));
  auto refill = [&](int r) {
    Source& s = from[static_cast<std::size_t>(r)];
    s.head = 0;
    if (r == 0) {
      s.n = std::min(kBatch, count - s.next);
      s.rows.resize(s.n * width);
      for (std::size_t e = 0; e < s.n; ++e) row(s.next + e, s.rows.data() + e * width);
      s.next += s.n;
    } else {
      comm::send_word(r, 1);
      s.n = static_cast<std::size_t>(comm::receive_word(r));
      s.rows.resize(s.n * width);
      if (s.n > 0) comm::receive_bytes(r, s.rows.data(), s.n * width * sizeof(double));
    }
    s.more = s.n == kBatch;
  };
  for (int r = 0; r < ranks; ++r) refill(r);
  std::exception_ptr failed;   // (rank 0's taking: every rank's rows are drawn to the end all the same)
  for (;;) {
    int best = -1;
    for (int r = 0; r < ranks; ++r) {
      const Source& s = from[static_cast<std::size_t>(r)];
      if (s.head < s.n && (best < 0 || before(&s.rows[s.head * width], &from[static_cast<std::size_t>(best)].rows[from[static_cast<std::size_t>(best)].head * width])))
        best = r;
    }
    if (best < 0) break;
    Source& s = from[static_cast<std::size_t>(best)];
    if (!failed) {
      try {
        take(&s.rows[s.head * width]);
      } catch (...) {
        failed = std::current_exception();
      }
    }
    if (++s.head == s.n && s.more) refill(best);
  }
  if (failed) std::rethrow_exception(failed);
}

void BrickStep::stream_ball_rows(const std::function<void(const double*)>& take, const Model* full, const Range* range) {
  if (!live_ || team_->shares_whole()) throw std::logic_error("internal error: balls streamed where no rank's part is live");
  const Balls& b = part_.balls;
  std::vector<std::uint32_t> order;
  together([&] {
    if (!range || range->empty()) order = owned_;
    else
      for (std::uint32_t k : owned_)
        if (holds(*full, *range, view_of(part_, k))) order.push_back(k);
    std::sort(order.begin(), order.end(), [&](std::uint32_t p, std::uint32_t q) { return b.id[p] < b.id[q]; });
  }, "listing its balls by id");
  merge_rows_to_root(order.size(), kBallRow, [&](std::size_t q, double* out) {
    const std::size_t k = order[q];
    out[0] = to_wire(b.id[k]);
    out[1] = b.type[k];
    std::size_t at = 2;
    for (const auto* v : {&b.x, &b.y, &b.z, &b.rad, &b.vx, &b.vy, &b.vz, &b.wx, &b.wy, &b.wz, &b.fx, &b.fy, &b.fz}) out[at++] = (*v)[k];
  }, [](const double* p, const double* q) { return row_id(p[0]) < row_id(q[0]); }, take);
}

void BrickStep::stream_contact_rows(bool bridges, const std::function<void(const double*)>& take, const Model* full,
                                    const Range* range) {
  if (!live_ || team_->shares_whole()) throw std::logic_error("internal error: contacts streamed where no rank's part is live");
  const ContactTable& c = part_.contacts;
  const auto& id = part_.balls.id;
  const bool results = results_left() && c.results_kept();
  const bool bridged = bridges && c.bridge.size() == c.size();
  std::vector<std::uint32_t> rows;
  together([&] { results_fault(); }, "gathering the contact results from the parts");
  const auto low = [&](std::size_t p) { return std::min(id[c.i[p]], id[c.j[p]]); };
  const auto high = [&](std::size_t p) { return std::max(id[c.i[p]], id[c.j[p]]); };
  const bool ranged = range && !range->empty();
  together([&] {
    std::vector<char> in;   // (where the range holds, on the part's balls: its own and its copies)
    if (ranged) {
      in.resize(part_.balls.size());
      for (std::size_t k = 0; k < in.size(); ++k) in[k] = holds(*full, *range, view_of(part_, k));
    }
    for (std::uint32_t p : owned_pairs_)
      if (((results && c.state[p] != 0) || (bridged && c.bridge[p] != 0)) && (!ranged || in[c.i[p]] || in[c.j[p]]))
        rows.push_back(p);
    // (Two images of one pair are one rank's, its ball i's owner's: they keep the list's order.)
    std::stable_sort(rows.begin(), rows.end(), [&](std::uint32_t p, std::uint32_t q) {
      return low(p) != low(q) ? low(p) < low(q) : high(p) < high(q);
    });
  }, "listing its contacts");
  const bool rolling = c.mrx.size() == c.size();
  merge_rows_to_root(rows.size(), kContactRow, [&](std::size_t q, double* out) {
    const std::size_t p = rows[q];
    const double s = id[c.i[p]] < id[c.j[p]] ? 1.0 : -1.0;
    out[0] = to_wire(low(p));
    out[1] = to_wire(high(p));
    const auto result = [&](const std::vector<double>& v) { return results ? v[p] : 0.0; };
    out[2] = s * result(c.nx); out[3] = s * result(c.ny); out[4] = s * result(c.nz);
    out[5] = result(c.overlap); out[6] = result(c.fn);
    out[7] = s * c.fsx[p]; out[8] = s * c.fsy[p]; out[9] = s * c.fsz[p];
    out[10] = rolling ? s * c.mrx[p] : 0.0; out[11] = rolling ? s * c.mry[p] : 0.0; out[12] = rolling ? s * c.mrz[p] : 0.0;
    out[13] = results ? c.state[p] : 0;
    out[14] = bridged ? c.bridge[p] : 0.0;
  }, [](const double* p, const double* q) {
    return row_id(p[0]) != row_id(q[0]) ? row_id(p[0]) < row_id(q[0]) : row_id(p[1]) < row_id(q[1]);
  }, take);
}

void BrickStep::vtk_ball_rows(const std::function<void(const double*)>& take) {
  if (!live_ || team_->shares_whole()) throw std::logic_error("internal error: a dump's balls streamed where no rank's part is live");
  merge_rows_to_root(owned_.size(), kVtkBallRow, [&](std::size_t q, double* out) {
    vtk_ball_row(part_.balls, owned_[q], out);
    out[0] = global_ball_[owned_[q]];
  }, [](const double* p, const double* q) { return p[0] < q[0]; }, take);
}

void BrickStep::vtk_line_rows(const Model& full, const std::function<void(const double*)>& take) {
  if (!live_ || team_->shares_whole()) throw std::logic_error("internal error: a dump's lines streamed where no rank's part is live");
  // (The pairs own_counts counts as touching: their count is Pipeline::part_counts' touching.)
  part_.space = full.space;   // (the cell as it is now, as own_stress)
  const ContactTable& c = part_.contacts;
  std::vector<std::uint32_t> rows;
  together([&] {
    if (c.results_kept())
      for (std::uint32_t p : owned_pairs_)
        if (c.state[p] != 0) rows.push_back(p);
  }, "listing its contacts");
  const CellFrame frame = cell_frame(part_.space);
  // (A rank's own pairs are those of its own balls i, in the whole list's order among themselves:
  // merged by ball i's place, they are the whole list's.)
  merge_rows_to_root(rows.size(), kVtkLineRow, [&](std::size_t q, double* out) {
    (void)vtk_line_row(part_, frame, rows[q], out);   // (each touches: own_lines)
    out[0] = global_ball_[part_.contacts.i[rows[q]]];
  }, [](const double* p, const double* q) { return p[0] < q[0]; }, take);
}

}  // namespace trubal
