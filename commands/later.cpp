// Commands of the language whose physics comes with later issues: they are in the table (HELP,
// completion, the man page) and say so clearly instead of doing something half-way.
#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

[[noreturn]] static void not_yet(std::string_view name, std::string_view what) {
  throw InputError(fmt::format("{} is not available yet in this version: it comes with {}", name, what));
}

static void run_membrane(Context&, Args&) { not_yet("MEMBRANE", "Rowe's triaxial test"); }
static void run_strain(Context&, Args&) { not_yet("STRAIN", "the strain-rate control of the periodic space"); }
static void run_servo(Context&, Args&) { not_yet("SERVO", "the stress servo of the periodic space"); }
static void run_plot(Context&, Args&) { not_yet("PLOT", "the plotting support (PNG/SVG via gnuplot)"); }
static void run_dump(Context&, Args&) { not_yet("DUMP", "the ParaView (VTK) output"); }

const Command membrane_command = {
    "MEMBRANE", {}, "MEMBRANE p [range ...]", "confining pressure on the outer balls (not available yet)",
    "Confining pressure p applied as forces on the outer balls of the range, each normal to the sample's "
    "lateral surface with its tributary area. Not available yet: it comes with Rowe's triaxial test.",
    {"range"}, run_membrane};

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

const Command plot_command = {
    "PLOT", {}, "PLOT what [file f.png]", "a picture of a history (not available yet)",
    "A picture of a history (e.g. ratio against axial) as PNG or SVG via gnuplot. Not available yet.",
    {"file", "line"}, run_plot};

const Command dump_command = {
    "DUMP", {}, "DUMP vtk file [every n]", "ParaView files of balls and contacts (not available yet)",
    "Ball positions, radii, velocities and contact forces as VTK files for ParaView. Not available yet.",
    {"vtk", "every"}, run_dump};

}  // namespace trubal
