// What happens on SIGINT or SIGTERM: the temporary files being written are
// removed (finished files and checkpoints stay), a line says what to do next,
// and the program exits with 128 + the signal number.
#pragma once

#include <filesystem>

namespace mpath {

// Installs the handlers; `advice` is printed after "interrupted; " (static string).
void install_interrupt_handlers(const char* program, const char* advice);

// Registers a temporary file for removal if the program is interrupted while
// it exists; the returned slot is released with forget_temporary.
int remember_temporary(const std::filesystem::path& path);
void forget_temporary(int slot);

}  // namespace mpath
