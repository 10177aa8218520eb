#pragma once
// The host's one way of writing a file a user asked for (parameters, reports, tables, logs, plot
// data): all of it or nothing, never a silent short file.

#include <string>
#include <string_view>

namespace dyncal::host {

/// Writes `bytes` to `path` so that afterwards `path` holds either all of `bytes` or, after any
/// failure, exactly what it held before (docs/reliability.md "Writes that cannot lie"):
/// - `path` must be a regular file (a symbolic link to one is followed) or a new name in an
///   existing folder; a FIFO, a device (/dev/full, /dev/null), a socket or a folder is refused;
/// - the bytes go to a temporary file in the same folder; every write, the flush to disk (fsync)
///   and the close are checked; the file is then renamed over `path` and the folder synced;
/// - a new file gets mode 0666 less the process's umask; a replaced file keeps its mode.
/// `what` names the file in the message ("parameters", "report", ...). Throws InputError, one line
/// naming `what`, the path and the system's reason (ENOSPC: "No space left on device"); the
/// temporary file is removed.
void write_output_file(const std::string& path, std::string_view bytes, const char* what = "output file");

/// Checks, before a long computation, that `path` can take an output (write_output_file's rules:
/// a regular file or a new name in an existing folder). Throws InputError as write_output_file.
void check_output_path(const std::string& path, const char* what = "output file");

}  // namespace dyncal::host
