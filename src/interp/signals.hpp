// Ctrl-C: while a command runs it asks the command to stop at the end of the current step.
#pragma once

#include <atomic>

namespace trubal {

std::atomic<bool>& interrupt_requested();
// Installs the SIGINT handler that sets interrupt_requested() (a second Ctrl-C while the flag is
// still set ends the program the usual way).
void install_interrupt_handler();

}  // namespace trubal
