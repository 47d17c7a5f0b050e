// Steps that nobody reads skip writing the per-contact results (normal, overlap, forces, work,
// state): only the last step of a run, the steps that history and dumps read, a step Ctrl-C ends
// and snapshot steps write them. These tests check that what is read is what every step writing
// everything would have given, to the bit, and that the lean steps move the balls identically.
#include <catch2/catch.hpp>

#include <atomic>
#include <vector>

#include "backends_scenes.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

std::vector<Scene> scenes() {
  std::vector<Scene> s;
  s.push_back(fcc_compression(4, 4, 4));
  s.push_back(settling(6, 3, 400));
  s.push_back(hertz_block(4));
  s.push_back(rayleigh_cloud(5));
  return s;
}

// Pictures taken after every 7th cycle. reads: whether the control says which cycles it reads
// (lean steps elsewhere) or leaves it unset (every step writes everything).
std::vector<Picture> record(Model model, const std::string& backend_name, int cycles, bool reads) {
  auto backend = make_pipeline(backend_name, backend_name == "serial" ? 1 : 2);
  std::vector<Picture> pictures;
  CycleControl control;
  control.after_step = [&](const Model& m) {
    if (m.cycle % 7 == 0) pictures.push_back(picture(m));
  };
  if (reads) control.reads_contacts = [](std::int64_t cycle) { return cycle % 7 == 0; };
  const CycleResult r = run_cycles(model, *backend, cycles, control);
  REQUIRE(!r.unstable);
  pictures.push_back(picture(model));
  return pictures;
}

}  // namespace

TEST_CASE("lean steps: what history reads equals a run that writes every step", "[physics][lean]") {
  for (const char* backend : {"serial", "threaded"}) {
    for (Scene& scene : scenes()) {
      INFO(scene.name << " on " << backend);
      const auto lean = record(scene.model, backend, scene.cycles, true);
      const auto full = record(scene.model, backend, scene.cycles, false);
      REQUIRE(lean.size() == full.size());
      REQUIRE(lean.size() > 2);
      for (std::size_t k = 0; k < lean.size(); ++k) {
        INFO("picture " << k << " at cycle " << lean[k].cycle);
        CHECK(difference(lean[k], full[k]).empty());
      }
    }
  }
}

TEST_CASE("lean steps: a run stopped by Ctrl-C ends on a step that wrote its contacts", "[physics][lean]") {
  for (Scene& scene : scenes()) {
    INFO(scene.name);
    Model stopped = scene.model;
    auto backend = make_pipeline("serial", 1);
    std::atomic<bool> interrupt{false};
    CycleControl control;
    control.interrupt = &interrupt;
    control.after_step = [&](const Model& m) {
      if (m.cycle == 41) interrupt = true;   // seen before the next step, which is the last
    };
    control.reads_contacts = [](std::int64_t) { return false; };
    const CycleResult r = run_cycles(stopped, *backend, scene.cycles, control);
    CHECK(r.interrupted);
    CHECK(r.done == 42);

    Model straight = scene.model;
    auto other = make_pipeline("serial", 1);
    REQUIRE(run_cycles(straight, *other, 42, {}).done == 42);
    CHECK(difference(picture(stopped), picture(straight)).empty());
  }
}
