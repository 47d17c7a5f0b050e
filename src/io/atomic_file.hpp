// Text files written whole or not at all: a temporary file beside the target, then a rename, so an
// interrupted or failed write never leaves half a file in place of a good one.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace trubal {

// Writes `text` to `path` through PATH.tmp-PID and a rename (no fsync: for outputs, not saves;
// SAVE syncs, io/save.cpp). Throws std::runtime_error naming the file; the temporary is removed.
void write_file_atomically(const std::string& path, const std::string& text);
// The same, the text written by `write` straight into the temporary (a table of millions of rows
// is never held in memory whole); what `write` throws removes the temporary and goes on.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

// Throws std::runtime_error unless `path` is absent or a regular file: a write through a temporary
// and a rename would replace a symbolic link or a device node with a regular file.
void check_replaceable(const std::string& path);

}  // namespace trubal
