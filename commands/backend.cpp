#include <thread>

#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_backend(Context& ctx, Args& args) {
  auto names = backend_names();
  std::vector<std::string_view> views(names.begin(), names.end());
  auto k = args.expect(views, "backend");
  int threads = 0;
  if (args.accept("threads")) threads = static_cast<int>(args.count("threads", 1, 4096));
  args.done();
  ctx.session.set_backend(names[k], threads);
  ctx.out << fmt::format("backend {} ({} threads)\n", ctx.session.backend().name(), ctx.session.backend().threads());
}

const Command backend_command = {
    "BACKEND", {}, "BACKEND serial|allpairs|threaded [threads n]", "choose how contacts are found",
    "Chooses the backend that finds contacts and sums forces; switching keeps balls, contacts and their shear "
    "history, and every backend gives the same numbers. serial: TRUBAL's boxes and contact lists.",
    {"serial", "allpairs", "threaded", "threads"}, run_backend};

}  // namespace trubal
