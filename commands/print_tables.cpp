// PRINT balls, contacts, walls and psd: the tables, to the screen or a CSV file (commands/print.cpp
// dispatches).
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "physics/bridge.hpp"
#include "cycle/pipeline.hpp"
#include "support/comm.hpp"
#include "support/peak_memory.hpp"
#include "model/wall_shape.hpp"
#include "physics/walls.hpp"
#include "io/atomic_file.hpp"
#include "io/csv.hpp"
#include "physics/measure.hpp"
#include "physics/measure_sphere.hpp"
#include "physics/scene.hpp"

#include "commands/print_parts.hpp"
#include "model/edit.hpp"

namespace trubal {

namespace {
constexpr auto row_id = &BrickStep::row_id;

// PRINT balls and contacts, of every ball and pair or a range's, from the rows the ranks' kept parts
// stream where rank 0's whole model is hollow (Session::rows_from_parts): the same text as from the
// whole model.
void print_balls_streamed(Context& ctx, const std::string& file, const Range& range) {
  std::size_t count = 0;
  if (!file.empty()) {
    write_file_atomically(file, [&](std::ostream& csv) {
      csv << "id,type,x,y,z,rad,vx,vy,vz,wx,wy,wz,fx,fy,fz\n";
      ctx.session.ball_rows([&](const double* r) {
        csv << row_id(r[0]) << ',' << static_cast<int>(r[1]);
        for (std::size_t k = 2; k < BrickStep::kBallRow; ++k) csv << ',' << csv_real(r[k]);
        csv << '\n';
        ++count;
      }, range);
    });
    ctx.out << fmt::format("{} written to {}\n", count_of(count, "ball"), file);
    return;
  }
  ctx.out << fmt::format("{:>8} {:>4} {:>12} {:>12} {:>12} {:>10} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11}\n", "id",
                         "type", "x", "y", "z", "rad", "vx", "vy", "vz", "fx", "fy", "fz");
  ctx.session.ball_rows([&](const double* r) {
    ctx.out << fmt::format("{:>8} {:>4} {:>12.6g} {:>12.6g} {:>12.6g} {:>10.4g} {:>11.4g} {:>11.4g} {:>11.4g} {:>11.4g} "
                           "{:>11.4g} {:>11.4g}\n",
                           row_id(r[0]), static_cast<int>(r[1]), r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[12], r[13], r[14]);
  }, range);
}

void print_contacts_streamed(Context& ctx, const std::string& file, const Range& range) {
  const Model& m = ctx.session.state();   // (the materials: which columns there are)
  const bool bridges = has_bridges(m), rolling = has_rolling(m);
  std::size_t count = 0;
  if (!file.empty()) {
    write_file_atomically(file, [&](std::ostream& csv) {
      csv << "i,j,nx,ny,nz,overlap,fn,fsx,fsy,fsz," << (rolling ? "mrx,mry,mrz," : "") << "sliding"
          << (bridges ? ",bridge\n" : "\n");
      ctx.session.contact_rows(bridges, [&](const double* r) {
        csv << row_id(r[0]) << ',' << row_id(r[1]);
        for (std::size_t k = 2; k < 10; ++k) csv << ',' << csv_real(r[k]);
        if (rolling)
          for (std::size_t k = 10; k < 13; ++k) csv << ',' << csv_real(r[k]);
        csv << ',' << (r[13] == 2 ? 1 : 0);
        if (bridges) csv << ',' << (r[14] != 0 ? 1 : 0);
        csv << '\n';
        ++count;
      }, range);
    });
    ctx.out << fmt::format("{} contacts written to {}\n", count, file);
    return;
  }
  ctx.out << fmt::format("{:>8} {:>8} {:>9} {:>9} {:>9} {:>11} {:>11} {:>11} {}{:>7}{}\n", "i", "j", "nx", "ny", "nz",
                         "overlap", "fn", "|fs|", rolling ? fmt::format("{:>11} ", "|mr|") : "", "sliding",
                         bridges ? "  bridge" : "");
  ctx.session.contact_rows(bridges, [&](const double* r) {
    ctx.out << fmt::format("{:>8} {:>8} {:>9.5f} {:>9.5f} {:>9.5f} {:>11.4g} {:>11.4g} {:>11.4g} {}{:>7}{}\n", row_id(r[0]),
                           row_id(r[1]), r[2], r[3], r[4], r[5], r[6], std::sqrt(r[7] * r[7] + r[8] * r[8] + r[9] * r[9]),
                           rolling ? fmt::format("{:>11.4g} ", std::sqrt(r[10] * r[10] + r[11] * r[11] + r[12] * r[12])) : "",
                           r[13] == 2 ? "yes" : "no", bridges ? (r[14] != 0 ? "     yes" : "      no") : "");
  }, range);
}
}  // namespace

void print_balls(Context& ctx, const Range& range, const std::string& file) {
  if (ctx.session.rows_from_parts()) return print_balls_streamed(ctx, file, range);
  const Model& m = ctx.session.model_but_results();   // (the unbalanced forces are the balls')
  const Balls& b = m.balls;
  auto sel = ctx.session.select(range);
  if (!comm::root()) return;   // (the table or file is rank 0's to print or write: the others' would go nowhere)
  std::sort(sel.begin(), sel.end(), [&](std::size_t p, std::size_t q) { return b.id[p] < b.id[q]; });   // by id
  if (!file.empty()) {
    write_file_atomically(file, [&](std::ostream& csv) {
      csv << "id,type,x,y,z,rad,vx,vy,vz,wx,wy,wz,fx,fy,fz\n";
      for (auto k : sel) {
        csv << b.id[k] << ',' << b.type[k];
        for (const auto* v : {&b.x, &b.y, &b.z, &b.rad, &b.vx, &b.vy, &b.vz, &b.wx, &b.wy, &b.wz, &b.fx, &b.fy, &b.fz})
          csv << ',' << csv_real((*v)[k]);
        csv << '\n';
      }
    });
    ctx.out << fmt::format("{} written to {}\n", count_of(sel.size(), "ball"), file);
    return;
  }
  ctx.out << fmt::format("{:>8} {:>4} {:>12} {:>12} {:>12} {:>10} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11}\n", "id",
                         "type", "x", "y", "z", "rad", "vx", "vy", "vz", "fx", "fy", "fz");
  for (auto k : sel)
    ctx.out << fmt::format("{:>8} {:>4} {:>12.6g} {:>12.6g} {:>12.6g} {:>10.4g} {:>11.4g} {:>11.4g} {:>11.4g} {:>11.4g} "
                           "{:>11.4g} {:>11.4g}\n",
                           b.id[k], b.type[k], b.x[k], b.y[k], b.z[k], b.rad[k], b.vx[k], b.vy[k], b.vz[k], b.fx[k],
                           b.fy[k], b.fz[k]);
}

void print_contacts(Context& ctx, const Range& range, const std::string& file) {
  if (ctx.session.rows_from_parts()) return print_contacts_streamed(ctx, file, range);
  const Model& m = ctx.session.model_but_results();
  const ContactTable& c = m.contacts;
  std::vector<bool> in(m.balls.size(), range.empty());
  if (!range.empty())
    for (auto k : ctx.session.select(range)) in[k] = true;
  if (!comm::root()) return;   // (as print_balls)
  // The results it prints, from the ranks' parts where the table does not hold them (the shear
  // force, the rolling moment and the bridges are the table's history): six of its arrays, not all.
  std::vector<std::uint8_t> state_fetched;
  std::vector<double> fetched[5];
  const std::vector<std::uint8_t>& state = ctx.session.results_of(c.state, state_fetched);
  const std::vector<double>& nx = ctx.session.results_of(c.nx, fetched[0]);
  const std::vector<double>& ny = ctx.session.results_of(c.ny, fetched[1]);
  const std::vector<double>& nz = ctx.session.results_of(c.nz, fetched[2]);
  const std::vector<double>& overlap = ctx.session.results_of(c.overlap, fetched[3]);
  const std::vector<double>& fn = ctx.session.results_of(c.fn, fetched[4]);
  const auto touching = [&](std::size_t p) { return p < state.size() && state[p] != 0; };
  // (Capillary bridges: the pairs they hold apart too, and a column saying which hold one.)
  const bool bridges = has_bridges(m) && c.bridge.size() == c.size();
  const auto printed = [&](std::size_t p) {
    return (touching(p) || (bridges && c.bridge[p] != 0)) && (in[c.i[p]] || in[c.j[p]]);
  };
  // The rows counted first and sorted in place: a million balls' list is no larger than it must be.
  std::size_t count = 0;
  for (std::size_t p = 0; p < c.size(); ++p) count += printed(p) ? 1 : 0;
  std::vector<std::size_t> rows;
  rows.reserve(count);
  for (std::size_t p = 0; p < c.size(); ++p)
    if (printed(p)) rows.push_back(p);
  const auto& id = m.balls.id;
  // Each pair as (smaller id, larger id), sorted so; a pair the model holds the other way round (its
  // order in memory is not id order) has its vectors on j turned round (s). Two images of one pair
  // (a small periodic cell) keep their order in the list.
  const auto low = [&](std::size_t p) { return std::min(id[c.i[p]], id[c.j[p]]); };
  const auto high = [&](std::size_t p) { return std::max(id[c.i[p]], id[c.j[p]]); };
  std::sort(rows.begin(), rows.end(), [&](std::size_t p, std::size_t q) {
    return low(p) != low(q) ? low(p) < low(q) : high(p) != high(q) ? high(p) < high(q) : p < q;
  });
  const auto s = [&](std::size_t p) { return id[c.i[p]] < id[c.j[p]] ? 1.0 : -1.0; };
  const bool rolling = has_rolling(m);   // (the rolling moment on j: columns only where a material has it)
  const bool rolling_kept = c.mrx.size() == c.size();   // (else zero: ContactTable::history_laws)
  const auto moment = [&](const std::vector<double>& v, std::size_t p) { return rolling_kept ? v[p] : 0.0; };
  if (!file.empty()) {
    write_file_atomically(file, [&](std::ostream& csv) {
      csv << "i,j,nx,ny,nz,overlap,fn,fsx,fsy,fsz," << (rolling ? "mrx,mry,mrz," : "") << "sliding"
          << (bridges ? ",bridge\n" : "\n");
      for (auto p : rows) {
        csv << low(p) << ',' << high(p);
        for (const auto* v : {&nx, &ny, &nz}) csv << ',' << csv_real(s(p) * (*v)[p]);
        for (const auto* v : {&overlap, &fn}) csv << ',' << csv_real((*v)[p]);
        for (const auto* v : {&c.fsx, &c.fsy, &c.fsz}) csv << ',' << csv_real(s(p) * (*v)[p]);
        if (rolling)
          for (const auto* v : {&c.mrx, &c.mry, &c.mrz}) csv << ',' << csv_real(s(p) * moment(*v, p));
        csv << ',' << (state[p] == 2 ? 1 : 0);
        if (bridges) csv << ',' << (c.bridge[p] != 0 ? 1 : 0);
        csv << '\n';
      }
    });
    ctx.out << fmt::format("{} contacts written to {}\n", rows.size(), file);
    return;
  }
  ctx.out << fmt::format("{:>8} {:>8} {:>9} {:>9} {:>9} {:>11} {:>11} {:>11} {}{:>7}{}\n", "i", "j", "nx", "ny", "nz",
                         "overlap", "fn", "|fs|", rolling ? fmt::format("{:>11} ", "|mr|") : "", "sliding",
                         bridges ? "  bridge" : "");
  for (auto p : rows)
    ctx.out << fmt::format("{:>8} {:>8} {:>9.5f} {:>9.5f} {:>9.5f} {:>11.4g} {:>11.4g} {:>11.4g} {}{:>7}{}\n", low(p),
                           high(p), s(p) * nx[p], s(p) * ny[p], s(p) * nz[p], overlap[p], fn[p],
                           std::sqrt(c.fsx[p] * c.fsx[p] + c.fsy[p] * c.fsy[p] + c.fsz[p] * c.fsz[p]),
                           rolling ? fmt::format("{:>11.4g} ", std::sqrt(moment(c.mrx, p) * moment(c.mrx, p) +
                                                                         moment(c.mry, p) * moment(c.mry, p) +
                                                                         moment(c.mrz, p) * moment(c.mrz, p)))
                                   : "",
                           state[p] == 2 ? "yes" : "no",
                           bridges ? (c.bridge[p] != 0 ? "     yes" : "      no") : "");
}

void print_walls(Context& ctx, const std::string& file) {
  const Model& m = ctx.session.state();   // (light state: PRINT)
  if (!file.empty()) {
    std::ostringstream csv;
    csv << "id,kind,type,x,y,z,nx,ny,nz,radius,vx,vy,vz,wx,wy,wz,rrate,fx,fy,fz,mx,my,mz,stress,contacts,work\n";
    for (const Wall& w : m.walls) {
      const Vec3 c = wall_centre(w);
      // No area, no stress: nan, as the screen's "(no area)" and HIST's w<n>_stress say it.
      const double stress = wall_servo_area(m, w) > 0 ? wall_stress(m, w) : std::numeric_limits<double>::quiet_NaN();
      csv << w.id << ',' << wall_kind_name(w.kind) << ',' << w.type;
      for (double v : {c[0], c[1], c[2], w.normal[0], w.normal[1], w.normal[2], w.radius, w.velocity[0], w.velocity[1],
                       w.velocity[2], w.spin[0], w.spin[1], w.spin[2], w.radius_rate, w.force[0], w.force[1], w.force[2],
                       w.moment[0], w.moment[1], w.moment[2], stress})
        csv << ',' << csv_real(v);
      csv << ',' << w.contacts << ',' << csv_real(w.work) << '\n';
    }
    write_file_atomically(file, csv.str());
    ctx.out << fmt::format("{} walls written to {}\n", m.walls.size(), file);
    return;
  }
  if (m.walls.empty()) { ctx.out << "no walls (WALL makes them)\n"; return; }
  for (const Wall& w : m.walls) {
    const Vec3 c = wall_centre(w);
    ctx.out << fmt::format("wall {} ({} of type {}): centre ({:.6g}, {:.6g}, {:.6g}), {} ({:.6g}, {:.6g}, {:.6g})", w.id,
                           wall_kind_name(w.kind), w.type, c[0], c[1], c[2], w.kind == WallKind::Cylinder ? "axis" : "normal",
                           w.normal[0], w.normal[1], w.normal[2]);
    if (w.kind == WallKind::Cylinder)
      ctx.out << fmt::format(", radius {:.6g}, length {:.6g}, balls {}", w.radius, w.length, w.inside ? "inside" : "outside");
    if (w.kind == WallKind::Polygon) ctx.out << fmt::format(", {} vertices", w.vertices.size());
    ctx.out << '\n';
    ctx.out << fmt::format("  velocity ({:.6g}, {:.6g}, {:.6g})  spin ({:.6g}, {:.6g}, {:.6g})", w.velocity[0], w.velocity[1],
                           w.velocity[2], w.spin[0], w.spin[1], w.spin[2]);
    if (w.kind == WallKind::Cylinder) ctx.out << fmt::format("  radius rate {:.6g}", w.radius_rate);
    if (w.servo_on) ctx.out << fmt::format("  servo to {:.6g}", w.servo_target);
    ctx.out << '\n';
    const double area = wall_servo_area(m, w);
    ctx.out << fmt::format("  force ({:.6g}, {:.6g}, {:.6g})  moment ({:.6g}, {:.6g}, {:.6g})  stress {}  contacts {}  "
                           "work {:.6g}\n",
                           w.force[0], w.force[1], w.force[2], w.moment[0], w.moment[1], w.moment[2],
                           area > 0 ? fmt::format("{:.6g}", wall_stress(m, w)) : std::string("(no area)"), w.contacts, w.work);
  }
}

// The grading of the balls the last GEN made (those still there) next to the one it asked for.
void print_psd(Context& ctx, const std::string& file) {
  const auto& sizes = ctx.session.last_sizes();
  if (!sizes) throw std::runtime_error("PRINT psd: no GEN since START or RESTART (it compares the last GEN's balls with its sizes)");
  const Model& m = ctx.session.state();   // (the radii and ids alone)
  std::vector<double> radii;
  for (std::int64_t id : ctx.session.last_generated())
    if (const std::int64_t k = find_ball(m, id); k >= 0) radii.push_back(m.balls.rad[static_cast<std::size_t>(k)]);
  if (radii.empty()) throw std::runtime_error("PRINT psd: the balls of the last GEN are gone");
  const auto rows = compare_grading(*sizes, radii);
  double worst = 0, at = 0;
  for (const auto& r : rows)
    if (std::abs(r.sample - r.asked) > worst) { worst = std::abs(r.sample - r.asked); at = r.diameter; }
  if (!file.empty()) {
    std::ostringstream csv;
    csv << "diameter,passing_asked,passing_sample\n";
    for (const auto& r : rows) csv << csv_real(r.diameter) << ',' << csv_real(r.asked) << ',' << csv_real(r.sample) << '\n';
    write_file_atomically(file, csv.str());
    ctx.out << fmt::format("grading at {} diameters written to {}\n", rows.size(), file);
  } else {
    ctx.out << fmt::format("grading of the last GEN's {} balls ({}), percent passing by mass:\n", radii.size(),
                           sizes->describe());
    ctx.out << fmt::format("{:>14} {:>10} {:>10} {:>10}\n", "diameter", "asked", "sample", "difference");
    for (const auto& r : rows)
      ctx.out << fmt::format("{:>14.6g} {:>10.3f} {:>10.3f} {:>10.3f}\n", r.diameter, r.asked, r.sample, r.sample - r.asked);
  }
  ctx.out << fmt::format("largest difference: {:.3f} percent passing, at diameter {:.6g}\n", worst, at);
}

}  // namespace trubal
