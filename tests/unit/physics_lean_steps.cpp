// Steps that nobody reads skip writing the per-contact results (normal, overlap, forces, work,
// state): only the last step of a run, the steps that history and dumps read, a step Ctrl-C ends
// and snapshot steps write them. These tests check that what is read is what every step writing
// everything would have given, to the bit, and that the lean steps move the balls identically.
#include <catch2/catch.hpp>

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

#include "backends_scenes.hpp"
#include "interp_support.hpp"

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

TEST_CASE("lean steps: what history reads equals a run that writes every step", "[physics][lean][threads]") {
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

// CYCLE's way (CycleControl::defer_results): the last step is lean too, the result arrays are
// freed, and make_results takes that step again from the rescue copy when they are read. What it
// makes is what a run writing the last step gives, to the bit, on every backend, and so is the
// state a second run goes on from.
TEST_CASE("lean steps: a run's last results, made when read, are those of a run that wrote them", "[physics][lean][threads]") {
  for (const char* backend : {"serial", "threaded"}) {
    for (Scene& scene : scenes()) {
      INFO(scene.name << " on " << backend);
      const int threads = std::string(backend) == "serial" ? 1 : 2;
      CycleControl deferring;
      deferring.defer_results = true;
      Model deferred = scene.model;
      auto pipeline = make_pipeline(backend, threads);
      const int first = scene.cycles / 3;   // not a multiple of 500: the copy is taken for the last step
      REQUIRE(run_cycles(deferred, *pipeline, first, deferring).done == first);
      CHECK_FALSE(deferred.contacts.results_kept());
      CHECK(deferred.contacts.nx.capacity() == 0);   // the memory went back
      CHECK(deferred.contacts.results_cycle == -1);
      CHECK(pipeline->results_deferred(deferred));

      Model straight = scene.model;
      auto other = make_pipeline(backend, threads);
      REQUIRE(run_cycles(straight, *other, first, {}).done == first);
      make_results(deferred, *pipeline);
      CHECK(deferred.contacts.results_cycle == deferred.cycle);
      CHECK_FALSE(pipeline->results_deferred(deferred));
      CHECK(difference(picture(deferred), picture(straight)).empty());

      // Deferred again, and the next run goes on from the deferred state (its rescue copy is the
      // step before): the same as the straight run.
      REQUIRE(run_cycles(deferred, *pipeline, 1, deferring).done == 1);
      REQUIRE(run_cycles(deferred, *pipeline, scene.cycles - first - 1, deferring).done == scene.cycles - first - 1);
      REQUIRE(run_cycles(straight, *other, scene.cycles - first, {}).done == scene.cycles - first);
      make_results(deferred, *pipeline);
      CHECK(difference(picture(deferred), picture(straight)).empty());
    }
  }
}

// The step taken again is checked against what it left (cycle, time, works, kinetic energy): a copy
// that is not of the step before cannot pass for it.
TEST_CASE("lean steps: results made from a copy that is not the step before are refused", "[physics][lean]") {
  // The copy put in is the same run's state at cycle 29 from a second run, as it is (accepted: the
  // check is on the state) and with one ball's velocity changed, as a change of the copy behind the
  // session's back would leave it (refused).
  CycleControl deferring;
  deferring.defer_results = true;
  for (const double change : {0.0, 1e-3}) {
    INFO("velocity changed by " << change);
    Scene scene = fcc_compression(4, 4, 4);
    auto pipeline = make_pipeline("serial", 1);
    REQUIRE(run_cycles(scene.model, *pipeline, 30, deferring).done == 30);
    Scene other = fcc_compression(4, 4, 4);
    REQUIRE(run_cycles(other.model, *make_pipeline("serial", 1), 29, {}).done == 29);
    other.model.balls.vx[0] += change;
    pipeline->take_rescue(other.model);
    REQUIRE(pipeline->results_deferred(scene.model));
    if (change == 0) CHECK_NOTHROW(make_results(scene.model, *pipeline));
    else CHECK_THROWS_AS(make_results(scene.model, *pipeline), std::logic_error);
  }
}

// Through the interpreter: CYCLE defers, any command that reads the model makes them, and a SAVE
// after it holds the bytes of a run that wrote them.
TEST_CASE("lean steps: CYCLE leaves its results to the next command that reads them", "[physics][lean][interp]") {
  test::TempDir dir;
  test::WorkingDir wd(dir.path());
  const std::string deck =
      "start box -10 10 -10 10 -10 10\nprop kn 1e5 ks 1e5 fric 0.5 dens 1000\n"
      "lattice fcc 1.0 4 4 4 origin 0 0 0\nini xvel 0.02 yvel -0.01 range id 1 9\n";
  test::Harness h;
  REQUIRE(h.deck(deck + "cycle 333\n"));
  CHECK_FALSE(h.session.state().contacts.results_kept());
  CHECK(h.session.pipeline().rescue().balls.size() == h.session.state().balls.size());   // of cycle 332
  const Model& m = h.session.model();
  CHECK(m.contacts.results_kept());
  CHECK(m.contacts.results_cycle == 333);
  // The copy they were made from is freed (its memory goes to the results) and of no cycle.
  CHECK(h.session.pipeline().rescue().balls.size() == 0);
  CHECK(h.session.pipeline().rescue().pairs.i.empty());
  CHECK(h.session.pipeline().rescue().cycle + 1 != m.cycle);
  REQUIRE(h.deck("save deferred.sav\n"));
  test::Harness straight;
  REQUIRE(straight.deck(deck));
  straight.session.cycle(333);   // the API's default: the last step writes them
  CHECK(straight.session.state().contacts.results_cycle == 333);
  straight.session.save("straight.sav");
  const std::string a = test::slurp(dir.path() / "deferred.sav"), b = test::slurp(dir.path() / "straight.sav");
  CHECK(!a.empty());
  CHECK(a == b);
  // A CYCLE after the copy was freed takes its own and goes on to the same bits.
  REQUIRE(h.deck("cycle 20\nsave deferred2.sav\n"));
  straight.session.cycle(20);
  straight.session.save("straight2.sav");
  CHECK(test::slurp(dir.path() / "deferred2.sav") == test::slurp(dir.path() / "straight2.sav"));
}
