// Commands of the language whose physics comes with later issues: they are in the table (HELP,
// completion, the man page) and say so clearly instead of doing something half-way.
#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

[[noreturn]] static void not_yet(std::string_view name, std::string_view what) {
  throw InputError(fmt::format("{} is not available yet in this version: it comes with {}", name, what));
}

static void run_strain(Context&, Args&) { not_yet("STRAIN", "the strain-rate control of the periodic space"); }
static void run_servo(Context&, Args&) { not_yet("SERVO", "the stress servo of the periodic space"); }

const Command strain_command = {
    "STRAIN", {}, "STRAIN e11 e22 e33 [e12 e13 e23]  |  STRAIN xx r ...  |  STRAIN off",
    "strain rates of the periodic space (not available yet)",
    "Strain rates of the periodic space (compression positive). Not available yet: it comes with the "
    "periodic-space control.",
    {"xx", "yy", "zz", "xy", "xz", "yz", "off"}, run_strain};

const Command servo_command = {
    "SERVO", {}, "SERVO s11 s22 s33 [gain g] [max rate]  |  SERVO xx s ...  |  SERVO off",
    "stress servo of the periodic space (not available yet)",
    "Drives the strain rates so that the average stress approaches the targets. Not available yet: it comes "
    "with the periodic-space control.",
    {"xx", "yy", "zz", "gain", "max", "off"}, run_servo};

}  // namespace trubal
