#include "cycle/step_scratch.hpp"

#include <algorithm>

namespace trubal {

void StepScratch::index(const ContactTable& table, std::size_t balls) {
  list_version = table.list_version;
  const std::size_t n = table.size();
  run_begin.assign(balls + 1, static_cast<std::uint32_t>(n));
  for (std::size_t p = n; p-- > 0;) run_begin[table.i[p]] = static_cast<std::uint32_t>(p);
  for (std::size_t b = balls; b-- > 0;) run_begin[b] = std::min(run_begin[b], run_begin[b + 1]);
  ball_force.assign(balls, PairForce{});
  ball_cn.assign(balls, 0.0);
  ball_parts.assign(balls, BallParts{});
}

void StepScratch::index_walls(const WallContacts& walls, std::size_t balls) {
  wall_list_version = walls.list_version;
  const std::size_t n = walls.size();
  wall_run_begin.assign(balls + 1, static_cast<std::uint32_t>(n));
  for (std::size_t p = n; p-- > 0;) wall_run_begin[walls.ball[p]] = static_cast<std::uint32_t>(p);
  for (std::size_t b = balls; b-- > 0;) wall_run_begin[b] = std::min(wall_run_begin[b], wall_run_begin[b + 1]);
}

}  // namespace trubal
